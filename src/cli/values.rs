//! The closed sets of values the command line takes that are no campaign setting (the camera presets, the
//! field-of-view estimate), each a `ValueEnum`, and [`choice`], the parser of a library [`Choice`] (a
//! setting's names are declared once, in the library). Either way `--help` lists the values and a typo fails
//! while parsing, before any file is read or any vehicle contacted.

use clap::ValueEnum;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use prgenuav::campaign::settings::Choice;
use prgenuav::lfs::camera::Camera;
use prgenuav::lfs::fov_estimate::FovEstimate;

/// The command-line name of a value (what `--help` lists).
#[cfg(test)]
pub fn name_of(v: &impl ValueEnum) -> String {
    v.to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// The parser of `T`'s names, as its [`Choice`] declares them.
pub fn choice<T: Choice + Clone + Send + Sync>() -> impl TypedValueParser<Value = T> {
    let values = T::names()
        .iter()
        .map(|(name, help)| PossibleValue::new(*name).help(*help));
    PossibleValuesParser::new(values).map(|name| T::named(&name).unwrap_or_else(|| unreachable!("a listed name")))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The names match the library's own parsers.
    #[test]
    fn names_match_the_library() {
        for c in CameraArg::value_variants() {
            assert_eq!(Camera::preset(&name_of(c)).map(|x| x.name), Some(c.model().name));
        }
        for f in FovEstimateArg::value_variants() {
            assert_eq!(FovEstimate::by_name(&name_of(f)), Some((*f).into()));
        }
    }
}
