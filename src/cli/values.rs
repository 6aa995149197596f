//! The closed sets of values the command line takes. Each is a `ValueEnum`, so `--help` lists the values and a
//! typo fails while parsing, before any file is read or any vehicle contacted. The library keeps its own types;
//! these convert at the boundary.

use clap::ValueEnum;
use prgenuav::bridge::FlyMode;
use prgenuav::judge::Judge;
use prgenuav::lfs::camera::Camera;
use prgenuav::lfs::fov_estimate::FovEstimate;
use prgenuav::lfs::sim::MotionModel;
use serde::{Deserialize, Serialize};

/// The command-line name of a value (what `--help` lists and what campaign files store).
pub fn name_of(v: &impl ValueEnum) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// Parses a value stored as text (campaign.json keeps `mode` and `motion` as strings), naming `what` and the
/// accepted values when it is none of them.
pub fn parse_stored<T: ValueEnum>(text: &str, what: &str) -> anyhow::Result<T> {
    T::from_str(text, false).map_err(|_| {
        let names: Vec<String> = T::value_variants().iter().map(name_of).collect();
        anyhow::anyhow!("{what} {text:?} is not one of {}", names.join(", "))
    })
}

/// Key spelling of written YAML files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpellingArg {
    /// `robot:` and `mission:` (Aerialist since 2025-09).
    New,
    /// `drone:` and `test:` (Aerialist before 2025-09, e.g. the 2025 competition's).
    Old,
}

impl From<SpellingArg> for prgenuav::model::Spelling {
    fn from(s: SpellingArg) -> Self {
        match s {
            SpellingArg::New => Self::New,
            SpellingArg::Old => Self::Old,
        }
    }
}

/// The low-fidelity simulator's motion model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Motion {
    /// PX4's waypoint generator and a PX4-like position tracker.
    Px4,
    /// The paper's kinematic rule towards the planner's first tree node.
    Paper,
}

impl Motion {
    /// The model with its fitted constants.
    pub fn model(self) -> MotionModel {
        match self {
            Motion::Px4 => MotionModel::Px4(Default::default()),
            Motion::Paper => MotionModel::Paper(Default::default()),
        }
    }
}

/// How a flight avoids the virtual obstacles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// PX4 <= 1.15 flies the mission with COM_OBS_AVOID = 1; prgenuav is its avoidance companion.
    Avoidance,
    /// prgenuav flies the waypoints in OFFBOARD mode with the planner's setpoints (any PX4).
    Offboard,
    /// PX4 flies the plain mission, no avoidance (the baseline).
    Mission,
    /// PX4's Collision Prevention is tested: prgenuav flies Position mode as a pilot and feeds a virtual lidar.
    CollisionPrevention,
}

impl From<Mode> for FlyMode {
    fn from(m: Mode) -> Self {
        match m {
            Mode::Avoidance => FlyMode::Avoidance,
            Mode::Offboard => FlyMode::Offboard,
            Mode::Mission => FlyMode::Mission,
            Mode::CollisionPrevention => FlyMode::CollisionPrevention,
        }
    }
}

/// The judge edition: which definition of a flight's distance to an obstacle counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum JudgeEdition {
    /// From the path buffered by half the vehicle width, horizontally (the current edition).
    #[value(name = "2026")]
    E2026,
    /// From the bare path, with the height-gap rule when the path passes over a box.
    #[value(name = "2025")]
    E2025,
}

impl From<JudgeEdition> for Judge {
    fn from(j: JudgeEdition) -> Self {
        match j {
            JudgeEdition::E2026 => Judge::E2026,
            JudgeEdition::E2025 => Judge::E2025,
        }
    }
}

/// A depth-camera preset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CameraArg {
    /// The competition's camera: 59 deg, 640 x 480.
    Hfs,
    /// The 2019 model PX4-Avoidance was tuned with: the competition's camera at 64 x 48.
    #[value(name = "2019")]
    V2019,
    /// The current SITL model (D455-like): 86 deg, 848 x 480.
    D455,
}

impl CameraArg {
    /// The preset's intrinsics and clipping.
    pub fn model(self) -> Camera {
        match self {
            CameraArg::Hfs => Camera::hfs(),
            CameraArg::V2019 => Camera::v2019(),
            CameraArg::D455 => Camera::d455(),
        }
    }
}

/// Where the planner's camera field of view comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FovEstimateArg {
    /// The pinhole span of the camera, fixed for the flight.
    Fixed,
    /// Estimated from each frame's extreme points, widened and never narrowed (as PX4-Avoidance does).
    Maxima,
}

impl From<FovEstimateArg> for FovEstimate {
    fn from(f: FovEstimateArg) -> Self {
        match f {
            FovEstimateArg::Fixed => FovEstimate::Fixed,
            FovEstimateArg::Maxima => FovEstimate::FromMaxima,
        }
    }
}

/// `--family`'s values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FamilyArg {
    /// The paper's two-obstacle S.
    Paper,
    /// The split drawn too, and a third obstacle where the case allows.
    Extended,
    /// Two boxes across the path with a gap around 2 x CP_DIST (the default with --mode collision-prevention).
    Gate,
}

impl From<FamilyArg> for prgenuav::generator::Family {
    fn from(f: FamilyArg) -> Self {
        match f {
            FamilyArg::Paper => Self::Paper,
            FamilyArg::Extended => Self::Extended,
            FamilyArg::Gate => Self::Gate,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names<T: ValueEnum>() -> Vec<String> {
        T::value_variants().iter().map(name_of).collect()
    }

    /// The names match the library's own parsers, so campaign files and the library agree on them.
    #[test]
    fn names_match_the_library() {
        for m in Motion::value_variants() {
            assert_eq!(
                MotionModel::by_name(&name_of(m)).map(|x| x.name()),
                Some(m.model().name())
            );
        }
        for c in CameraArg::value_variants() {
            assert_eq!(Camera::preset(&name_of(c)).map(|x| x.name), Some(c.model().name));
        }
        for f in FovEstimateArg::value_variants() {
            assert_eq!(FovEstimate::by_name(&name_of(f)), Some((*f).into()));
        }
        for j in JudgeEdition::value_variants() {
            assert_eq!(name_of(j).parse::<Judge>(), Ok((*j).into()));
        }
        assert_eq!(parse_stored::<Mode>("offboard", "mode").ok(), Some(Mode::Offboard));
        for m in Mode::value_variants() {
            let mode = prgenuav::campaign::setup::fly_mode(&name_of(m)).ok();
            assert_eq!(mode, Some((*m).into()));
        }
        let declared = |section, key| -> Vec<String> {
            let s = prgenuav::campaign::settings::find(section, key).unwrap();
            s.choices.iter().map(|(n, _)| n.to_string()).collect()
        };
        assert_eq!(declared("screening", "motion"), names::<Motion>());
        assert_eq!(declared("output", "spelling"), names::<SpellingArg>());
        assert_eq!(declared("generator", "family"), names::<FamilyArg>());
        let e = parse_stored::<Mode>("ofboard", "mode").unwrap_err().to_string();
        assert!(e.contains("avoidance, offboard, mission"), "{e}");
    }
}
