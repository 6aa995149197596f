//! The UAV Testing Competition's facts, one named constant each, so a rule change is a one-line edit.
//!
//! Source of every value: the competition's rules, scoring and frames as summarised in `docs/formats.md`
//! (taken from the competition repository at `ICST/SBFT_2025` and the Aerialist test bench). Distances are
//! metres in the local frame (`x` North, `y` East), angles degrees, times seconds.

use super::arena::{Arena, Range};

/// A run whose minimum distance is below this is a (soft) failure, metres (`docs/formats.md`, judging).
pub const FAIL_BELOW_M: f64 = 1.5;

/// A run's points by its minimum distance, metres: the first row whose bound the distance is below wins,
/// none gives 0 (`docs/formats.md`, scoring: 5 below 0.25 m, 2 below 1 m, 1 below 1.5 m).
pub const RUN_POINTS: [(f64, u32); 3] = [(0.25, 5), (1.0, 2), (FAIL_BELOW_M, 1)];

/// A test's score is mean points x this / (obstacles^2 x mean flight minutes) (`docs/formats.md`, scoring).
pub const TEST_SCORE_SCALE: f64 = 10.0;

/// Aerialist's `VEHICLE_WIDTH`, metres: the newer judge buffers the path by half of it (`docs/formats.md`,
/// judging).
pub const VEHICLE_WIDTH_M: f64 = 0.25;

/// Half of [`VEHICLE_WIDTH_M`], metres: how much smaller the newer judge's distance is.
pub const HALF_VEHICLE_WIDTH_M: f64 = VEHICLE_WIDTH_M / 2.0;

/// Aerialist averages the flown path into bins of this length before judging, seconds (`docs/formats.md`,
/// judging).
pub const AERIALIST_BIN_S: f64 = 0.5;

/// North extent of the obstacle-designated area (ODA) and range of an obstacle centre's `x`, metres
/// (`docs/formats.md`, rules).
pub const ODA_X_M: Range = Range::new(-40.0, 30.0);

/// East extent of the ODA and range of an obstacle centre's `y`, metres (`docs/formats.md`, rules).
pub const ODA_Y_M: Range = Range::new(10.0, 40.0);

/// Allowed box length `l`, metres (`docs/formats.md`, rules).
pub const BOX_LENGTH_M: Range = Range::new(2.0, 20.0);

/// Allowed box width `w`, metres (`docs/formats.md`, rules).
pub const BOX_WIDTH_M: Range = Range::new(2.0, 20.0);

/// Allowed box height `h`, metres; a box must also be taller than [`FLIGHT_ALTITUDE_M`] (`docs/formats.md`,
/// rules).
pub const BOX_HEIGHT_M: Range = Range::new(10.0, 25.0);

/// Allowed box rotation `r`, degrees counter-clockwise from `x` (`docs/formats.md`, rules).
pub const BOX_ROTATION_DEG: Range = Range::new(0.0, 90.0);

/// The public missions' flight altitude, metres above home (`docs/formats.md`, frames).
pub const FLIGHT_ALTITUDE_M: f64 = 10.0;

/// Most obstacles in one test (`docs/formats.md`, rules; fewer score more).
pub const MAX_OBSTACLES: usize = 3;

/// The vehicle parameters every case study sets before the flight (`mission-params.csv`, `docs/formats.md`,
/// files): PX4 parameter name and value.
pub const MISSION_PARAMS: [(&str, f64); 8] = [
    ("NAV_ACC_RAD", 0.5),
    ("NAV_MC_ALT_RAD", 0.5),
    ("NAV_RCL_ACT", 3.0),
    ("NAV_DLL_ACT", 0.0),
    ("MIS_YAW_ERR", 12.0),
    ("MIS_TAKEOFF_ALT", 1.0),
    ("MPC_YAW_MODE", 0.0),
    ("SDLOG_PROFILE", 7.0),
];

/// Wall-clock limit of one simulation in the competition's protocol, seconds (`docs/formats.md`, scoring).
pub const SIMULATION_TIMEOUT_S: f64 = 500.0;

/// The shortest flight a score counts, seconds. A test score divides by the flight time, so a record of a
/// moment scores absurdly (two samples 1 us apart: 1.2e9 points a minute). No competition mission flies in less:
/// landing from the 10 m flight altitude alone takes 14 s at PX4's landing speed (0.7 m/s).
pub const MIN_FLIGHT_S: f64 = 10.0;

/// Why a recorded flight of `duration_s` seconds cannot be scored, if it cannot ([`MIN_FLIGHT_S`]).
pub fn flight_time_rule(duration_s: f64) -> Option<String> {
    (duration_s < MIN_FLIGHT_S).then(|| {
        format!(
            "the flight lasts {duration_s:.3} s: a flight shorter than {MIN_FLIGHT_S} s is not a mission flown (landing \
             from the flight altitude alone takes longer), and a test score divides by the flight time"
        )
    })
}

impl Arena {
    /// The 2025/2026 competition's rules, from the constants above.
    pub const COMPETITION: Arena = Arena {
        x: ODA_X_M,
        y: ODA_Y_M,
        l: BOX_LENGTH_M,
        w: BOX_WIDTH_M,
        h: BOX_HEIGHT_M,
        r: BOX_ROTATION_DEG,
        flight_altitude_m: FLIGHT_ALTITUDE_M,
        max_obstacles: MAX_OBSTACLES,
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_width_is_exact() {
        assert_eq!(HALF_VEHICLE_WIDTH_M, 0.125);
    }

    #[test]
    fn a_flight_of_a_moment_is_not_scored() {
        let why = flight_time_rule(1e-6).unwrap();
        assert!(why.contains("0.000 s") && why.contains("shorter than 10 s"), "{why}");
        assert_eq!(flight_time_rule(MIN_FLIGHT_S), None);
    }
}
