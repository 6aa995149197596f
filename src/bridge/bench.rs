//! Named benches (`--bench`): what a `--px4` flight sets beyond the build and the test so that it flies the
//! way a given simulator flew. `plain` adds nothing. `competition` reproduces, as far as prgenuav's evidence
//! goes, the simulator the UAV Testing Competition judges on (PX4 v1.12.3 SITL, the Gazebo Classic iris,
//! PX4-Avoidance; docs/validation/competition-bench.md): PX4 v1.12 only, prgenuav's iris, its nose East at
//! rest as Gazebo spawns it, and the PX4 parameter chosen by cross-validation on the recorded flights.

use super::options::VehicleSim;
use super::px4_version::Px4Version;
use crate::model::{Param, TestCase};

/// A named bench.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Bench {
    /// The build, the simulator and the test's parameters as given.
    #[default]
    Plain,
    /// The competition's simulator as reproduced here ([`COMPETITION`]).
    Competition,
}

/// What a bench sets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BenchProfile {
    /// The simulator it flies.
    pub sim: VehicleSim,
    /// The PX4 releases (major, minor) it was checked on; any other is refused.
    pub releases: &'static [(u32, u32)],
    /// The vehicle's nose at rest, degrees clockwise from North.
    pub heading_deg: f64,
    /// PX4 parameters set after the test's own (they win over the test's).
    pub params: &'static [(&'static str, f64)],
    /// The most obstacles of the tests it was checked on; a test with more is flown with a caveat.
    pub checked_obstacles: usize,
    /// A box whose top lies less than this above the flight altitude, metres, is flown with a caveat: the
    /// vehicle may cross over it (0: no caveat).
    pub low_box_margin_m: f64,
}

/// The competition's bench. Gazebo Classic spawns the iris at ENU yaw 0 (Aerialist's launch file gives no
/// `-Y`): facing East. MPC_XY_CRUISE 2.3: the cruise speed both PX4 and the avoidance companion read (the
/// companion's setpoint lead), chosen by cross-validation with folds by obstacle set among 1.8, 2.3, 3.0
/// and MPC_XY_VEL_MAX 1.3 or 1.5 (docs/validation/competition-bench-fit.md): held out, the free-flight time
/// ratio went from 0.65 to 1.03 and the distance error from 1.33 to 0.93 m.
pub const COMPETITION: BenchProfile = BenchProfile {
    sim: VehicleSim::Iris,
    releases: &[(1, 12)],
    heading_deg: 90.0,
    params: &[("MPC_XY_CRUISE", 2.3)],
    // 49 of the 50 recorded cases it was fitted on have 1 or 2 boxes; the one with 3 hovered to the timeout.
    checked_obstacles: 2,
    // 28 of the 50 fitted cases have a box at most 1.7 m above the 10 m flight (26 exactly 10 m): there the
    // bench erred more (median 0.93 m against 0.72 m) and all 3 of its timeouts were among them.
    low_box_margin_m: 2.0,
};

/// Nothing added.
const PLAIN: BenchProfile = BenchProfile {
    sim: VehicleSim::Sih,
    releases: &[],
    heading_deg: 0.0,
    params: &[],
    checked_obstacles: usize::MAX,
    low_box_margin_m: 0.0,
};

impl BenchProfile {
    /// The test as this bench flies it: its parameters, then the bench's (the flown copy; the test written
    /// out stays the test).
    pub fn flown(&self, test: &TestCase) -> TestCase {
        let mut t = test.clone();
        for (name, value) in self.params {
            Param::set(&mut t.params, name, *value);
        }
        t
    }

    /// What in `test` this bench was not checked on, one sentence each: the test is flown all the same and
    /// each caveat is said with the flight (its report's warnings; `generate` and `evaluate` say it once and
    /// journal it).
    pub fn caveats(&self, test: &TestCase) -> Vec<String> {
        let mut out = Vec::new();
        let n = test.obstacles.len();
        if n > self.checked_obstacles {
            out.push(format!(
                "{n} obstacles: this bench was checked on tests with at most {} (flown as given; its distance is \
                 not checked against the competition's simulator)",
                self.checked_obstacles
            ));
        }
        let altitude = test.mission.cruise_altitude_m();
        for (i, o) in test.obstacles.iter().enumerate() {
            let above = o.size.h - altitude;
            if above < self.low_box_margin_m {
                out.push(format!(
                    "simulation.obstacles[{i}] is {:.1} m high, {above:.1} m above the flight altitude {altitude:.1} m: \
                     the vehicle may cross over it; the report says when a run came closest above a box's top \
                     (the 2026 judge scores such a crossing 0 m)",
                    o.size.h
                ));
            }
        }
        out
    }
}

impl Bench {
    /// What it sets.
    pub fn profile(self) -> &'static BenchProfile {
        match self {
            Bench::Plain => &PLAIN,
            Bench::Competition => &COMPETITION,
        }
    }

    /// The simulator it flies when `--sim` is not given.
    pub fn sim(self) -> VehicleSim {
        self.profile().sim
    }

    /// Whether it flies with `sim` given by the user: the plain bench with any, a named one with its own.
    pub fn sim_refusal(self, sim: VehicleSim) -> Option<String> {
        (self != Bench::Plain && sim != self.sim()).then(|| {
            format!(
                "--bench {} flies prgenuav's iris simulator (the competition's Gazebo iris): give --sim iris or \
                 leave --sim out",
                self.name()
            )
        })
    }

    /// Whether a build of `version` may fly this bench: a named bench is refused on a release it was not
    /// checked on, by name.
    pub fn release_refusal(self, version: &Px4Version) -> Option<String> {
        let p = self.profile();
        if p.releases.is_empty() || p.releases.contains(&(version.major, version.minor)) {
            return None;
        }
        let checked: Vec<String> = p.releases.iter().map(|(a, b)| format!("v{a}.{b}")).collect();
        Some(format!(
            "--bench {} was checked on PX4 {} only (the competition's release is v1.12.3); this build is PX4 \
             {version}: build v1.12.3 (docs/px4-versions.md), or fly without --bench",
            self.name(),
            checked.join(", ")
        ))
    }

    /// The test as this bench flies it ([`BenchProfile::flown`]).
    pub fn flown(self, test: &TestCase) -> TestCase {
        self.profile().flown(test)
    }

    /// What in `test` this bench was not checked on ([`BenchProfile::caveats`]).
    pub fn caveats(self, test: &TestCase) -> Vec<String> {
        self.profile().caveats(test)
    }

    /// The vehicle's nose at rest, degrees clockwise from North.
    pub fn heading_deg(self) -> f64 {
        self.profile().heading_deg
    }

    fn name(self) -> &'static str {
        match self {
            Bench::Plain => "plain",
            Bench::Competition => "competition",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn version(text: &str) -> Px4Version {
        Px4Version::parse(text).expect("a version")
    }

    #[test]
    fn the_competition_bench_flies_v1_12_only_and_names_the_build_it_refuses() {
        let c = Bench::Competition;
        assert_eq!(c.release_refusal(&version("v1.12.3")), None);
        let e = c
            .release_refusal(&version("v1.14.0-beta2-325-g1555f2bd22"))
            .expect("refused");
        assert!(
            e.contains("v1.14.0-beta2-325-g1555f2bd22") && e.contains("v1.12"),
            "{e}"
        );
        assert_eq!(Bench::Plain.release_refusal(&version("v1.16.2")), None);
    }

    #[test]
    fn a_third_box_and_a_low_box_are_flown_with_a_caveat_each_on_the_competition_bench_only() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission1.yaml");
        let mut test = TestCase::load(&path).expect("mission 1");
        let altitude = test.mission.cruise_altitude_m();
        let boxed = |x: f64, h: f64| crate::model::Obstacle::new(2.0, 2.0, h, x, 20.0, 0.0);
        test.obstacles = vec![boxed(-20.0, 20.0), boxed(0.0, 20.0)];
        assert!(Bench::Competition.caveats(&test).is_empty());
        test.obstacles.push(boxed(20.0, altitude + 1.5));
        let c = Bench::Competition.caveats(&test);
        assert_eq!(c.len(), 2, "{c:?}");
        assert!(
            c[0].starts_with("3 obstacles") && c[0].contains("at most 2"),
            "{}",
            c[0]
        );
        assert!(
            c[1].starts_with("simulation.obstacles[2]") && c[1].contains("1.5 m above"),
            "{}",
            c[1]
        );
        assert!(Bench::Plain.caveats(&test).is_empty());
    }

    #[test]
    fn the_competition_bench_flies_the_iris_and_refuses_sih() {
        assert_eq!(Bench::Competition.sim(), VehicleSim::Iris);
        assert_eq!(Bench::Plain.sim(), VehicleSim::Sih);
        assert!(Bench::Competition.sim_refusal(VehicleSim::Sih).is_some());
        assert_eq!(Bench::Competition.sim_refusal(VehicleSim::Iris), None);
        assert_eq!(Bench::Plain.sim_refusal(VehicleSim::Iris), None);
    }

    #[test]
    fn the_bench_parameters_win_over_the_tests_on_the_flown_copy_only() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission1.yaml");
        let mut test = TestCase::load(&path).expect("mission 1");
        test.params.push(Param {
            name: "MPC_XY_VEL_MAX".into(),
            value: 12.0,
        });
        let capped = BenchProfile {
            params: &[("MPC_XY_VEL_MAX", 1.5)],
            ..COMPETITION
        };
        let flown = capped.flown(&test);
        let vel: Vec<f64> = flown
            .params
            .iter()
            .filter(|p| p.name == "MPC_XY_VEL_MAX")
            .map(|p| p.value)
            .collect();
        assert_eq!(vel, [1.5]);
        assert_eq!(flown.params.len(), test.params.len());
        let competition = Bench::Competition.flown(&test);
        for (name, value) in COMPETITION.params {
            assert!(
                competition.params.iter().any(|p| p.name == *name && p.value == *value),
                "{name}"
            );
        }
        assert!(
            test.params
                .iter()
                .any(|p| p.name == "MPC_XY_VEL_MAX" && p.value == 12.0)
        );
        assert_eq!(Bench::Plain.flown(&test), test);
        assert_eq!(Bench::Competition.heading_deg(), 90.0);
    }
}
