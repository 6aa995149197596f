//! Where the vehicle stands against the test's home, as found before anything is uploaded or armed (found by
//! [`super::anchor`]).
//!
//! 1. HOME_POSITION (asked for once). 2. PX4 refuses a mission whose first waypoint is farther than MIS_DIST_1WP
//!    from the vehicle (PX4 v1.14 `src/modules/navigator/MissionFeasibility/FeasibilityChecker.cpp` line 608,
//!    default 900 m in `src/modules/navigator/mission_params.c` line 89): a vehicle whose home is farther than
//!    that from the test's home is refused here, before the upload, unless the test is re-anchored at the
//!    vehicle's home ([`ANCHOR_OPTION`], [`crate::model::TestCase::anchored_at`]). 3. The offset of the EKF
//!    origin in the test's frame ([`crate::bridge::companion::frame`]): GPS_GLOBAL_ORIGIN (asked for with MAV_CMD_REQUEST_MESSAGE
//!    49, since PX4 sends it only once and on change), or a GLOBAL_POSITION_INT as a fallback.

use serde::Serialize;

use crate::model::GeoPoint;

/// The option that re-anchors a test at the vehicle's home (named in refusals).
pub const ANCHOR_OPTION: &str = "--anchor-at-vehicle-home";
/// PX4 v1.14's MIS_DIST_1WP default, metres (`mission_params.c` line 89), used if the vehicle has no such
/// parameter.
pub const MIS_DIST_1WP_DEFAULT_M: f64 = 900.0;

/// A latitude/longitude/altitude as reported.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LatLonAlt {
    /// Degrees North.
    pub lat_deg: f64,
    /// Degrees East.
    pub lon_deg: f64,
    /// Metres AMSL (0 for box centres, which are on the ground of the test's home).
    pub alt_m: f64,
}

impl From<GeoPoint> for LatLonAlt {
    fn from(g: GeoPoint) -> Self {
        Self {
            lat_deg: g.lat_deg,
            lon_deg: g.lon_deg,
            alt_m: g.alt_m,
        }
    }
}

/// Where the vehicle stood against the test's home.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VehiclePlacement {
    /// The vehicle's HOME_POSITION.
    pub vehicle_home: LatLonAlt,
    /// The test's home it was compared with (after re-anchoring: the vehicle's home).
    pub test_home: LatLonAlt,
    /// Horizontal distance from the test's (original) home to the vehicle's, metres.
    pub distance_m: f64,
    /// The vehicle's MIS_DIST_1WP, metres (`None`: not readable, PX4's default assumed).
    pub mis_dist_1wp_m: Option<f64>,
    /// The test was re-anchored at the vehicle's home.
    pub anchored: bool,
    /// Refused: farther than MIS_DIST_1WP without re-anchoring.
    pub too_far: bool,
    /// Where the boxes' centres are (latitude, longitude about the flown test's home).
    pub obstacle_centres: Vec<LatLonAlt>,
}

/// Whether a vehicle `distance_m` from the test's home may fly it unanchored: `limit_m` <= 0 disables PX4's
/// check, as in PX4.
pub fn too_far(distance_m: f64, limit_m: f64) -> bool {
    limit_m > 0.0 && distance_m > limit_m
}

/// The refusal's words.
pub fn too_far_reason(distance_m: f64, limit_m: f64) -> String {
    format!(
        "the vehicle's home is {distance_m:.0} m from the test's home, farther than MIS_DIST_1WP ({limit_m:.0} m): PX4 \
         would refuse the mission; fly with {ANCHOR_OPTION} to re-anchor the test (mission, obstacles, fence) where \
         the vehicle stands"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn px4s_first_waypoint_rule() {
        assert!(!too_far(899.0, 900.0));
        assert!(too_far(901.0, 900.0));
        assert!(!too_far(1e6, 0.0), "0 disables the check, as in PX4");
        assert!(!too_far(1e6, -1.0));
        let r = too_far_reason(1234.4, 900.0);
        assert!(
            r.contains(ANCHOR_OPTION) && r.contains("1234 m") && r.contains("900 m"),
            "{r}"
        );
    }
}
