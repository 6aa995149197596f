//! Angles, wraps and histogram index maps of 3DVFH* (docs/planner.md §1.2-1.4 and §4), in f32 as the original.
//!
//! Two polar conventions exist, both about an origin in the planner's ENU world frame (x East, y North, z Up):
//! * **histogram polar** ([`cartesian_to_polar_histogram`]): azimuth `z_deg` is a compass bearing (0 = North (+y),
//!   growing clockwise seen from above, so +90 = East), elevation `e_deg` is positive up;
//! * **FCU polar** ([`cartesian_to_polar_fcu`]): azimuth counter-clockwise from East (as ENU yaw), elevation positive
//!   **down**. It is only used for field-of-view tests.

use nalgebra::Vector3;

/// Histogram cell size in degrees (`ALPHA_RES`).
pub const ALPHA_RES: i32 = 6;
/// Number of elevation rows of the 6-degree histogram (180 / 6).
pub const GRID_E: usize = 30;
/// Number of azimuth columns of the 6-degree histogram (360 / 6).
pub const GRID_Z: usize = 60;
/// Number of cells of the 6-degree histogram.
pub const GRID_CELLS: usize = GRID_E * GRID_Z;

/// Degrees to radians as the original computes it in f32 (`M_PI_F / 180.f`).
pub const DEG_TO_RAD: f32 = std::f32::consts::PI / 180.0;
/// Radians to degrees as the original computes it in f32 (`180.f / M_PI_F`).
pub const RAD_TO_DEG: f32 = 180.0 / std::f32::consts::PI;

/// A direction plus range. Angles in degrees; which convention (histogram or FCU) depends on the producer.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PolarDeg {
    /// Elevation in degrees (histogram polar: positive up; FCU polar: positive down).
    pub e_deg: f32,
    /// Azimuth in degrees (histogram polar: clockwise from North; FCU polar: counter-clockwise from East).
    pub z_deg: f32,
    /// Range in metres.
    pub r_m: f32,
}

impl PolarDeg {
    /// Builds a polar point from elevation and azimuth in degrees and a range in metres.
    pub const fn new(e_deg: f32, z_deg: f32, r_m: f32) -> Self {
        Self { e_deg, z_deg, r_m }
    }
}

/// A cell of a polar grid: row `e` (elevation, 0 = lowest) and column `z` (azimuth, 0 = -180 deg, South).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CellIndex {
    /// Elevation row.
    pub e: usize,
    /// Azimuth column.
    pub z: usize,
}

/// Exactly `x.floor()` without a libm call (baseline x86-64 has no rounding instruction; `floorf` showed up in
/// profiles). Values of magnitude >= 2^23 are already integers; NaN stays NaN.
#[inline]
pub fn floor_f32(x: f32) -> f32 {
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        if t > x { t - 1.0 } else { t }
    } else {
        x
    }
}

/// Wraps an angle to [-180, 180): `a - 360 floor(a/360 + 1/2)`, so +180 maps to -180.
#[inline]
pub fn wrap_180(a_deg: f32) -> f32 {
    a_deg - 360.0 * floor_f32(a_deg / 360.0 + 0.5)
}

/// Wraps an angle in radians to [-pi, pi) with the same rule as [`wrap_180`].
pub fn wrap_pi(a_rad: f32) -> f32 {
    let two_pi = 2.0 * std::f32::consts::PI;
    a_rad - two_pi * floor_f32(a_rad / two_pi + 0.5)
}

/// An elevation in [-180, 180) folded back over the pole it passed, and whether it was (the azimuth then turns
/// by 180 degrees).
#[inline]
pub fn fold_elevation_deg(e: f32) -> (f32, bool) {
    if e > 90.0 {
        (180.0 - e, true)
    } else if e < -90.0 {
        (-(180.0 + e), true)
    } else {
        (e, false)
    }
}

/// Polar wrap: both angles to [-180, 180), then an elevation beyond a pole is folded back and the azimuth
/// turned by 180 degrees towards zero.
pub fn wrap_polar(p: PolarDeg) -> PolarDeg {
    let (e, wrapped) = fold_elevation_deg(wrap_180(p.e_deg));
    let mut z = wrap_180(p.z_deg);
    if wrapped {
        z = if z < 0.0 { z + 180.0 } else { z - 180.0 };
    }
    PolarDeg {
        e_deg: e,
        z_deg: z,
        r_m: p.r_m,
    }
}

/// Signed difference `a - b` in degrees brought into [-180, 180) via `fmod` (the original `angleDifference`).
pub fn angle_difference(a_deg: f32, b_deg: f32) -> f32 {
    let d = a_deg - b_deg;
    // fmod is exact and the identity below 360 in magnitude; skip the libm call there. The call sits in a cold
    // function so that vectorised callers do not evaluate it speculatively for every lane.
    let angle = if d.abs() < 360.0 { d } else { fmod_360(d) };
    if angle >= 0.0 {
        if angle < 180.0 { angle } else { angle - 360.0 }
    } else if angle >= -180.0 {
        angle
    } else {
        angle + 360.0
    }
}

/// `d % 360` (C `fmod`), out of line.
#[cold]
#[inline(never)]
fn fmod_360(d: f32) -> f32 {
    d % 360.0
}

/// Histogram polar of `p` seen from `origin` (both ENU, metres). Azimuth in (-180, 180], elevation in [-90, 90].
pub fn cartesian_to_polar_histogram(p: &Vector3<f32>, origin: &Vector3<f32>) -> PolarDeg {
    let dx = p.x - origin.x;
    let dy = p.y - origin.y;
    let dz = p.z - origin.z;
    let den = (dx * dx + dy * dy).sqrt();
    PolarDeg {
        e_deg: dz.atan2(den) * RAD_TO_DEG,
        z_deg: dx.atan2(dy) * RAD_TO_DEG,
        r_m: (dx * dx + dy * dy + dz * dz).sqrt(),
    }
}

/// ENU point at histogram polar `p` from `origin`.
pub fn polar_histogram_to_cartesian(p: &PolarDeg, origin: &Vector3<f32>) -> Vector3<f32> {
    let (e, z) = (p.e_deg * DEG_TO_RAD, p.z_deg * DEG_TO_RAD);
    Vector3::new(
        origin.x + p.r_m * e.cos() * z.sin(),
        origin.y + p.r_m * e.cos() * z.cos(),
        origin.z + p.r_m * e.sin(),
    )
}

/// FCU polar of `p` from `origin`: azimuth = 90 - histogram azimuth, elevation = -histogram elevation, wrapped.
pub fn cartesian_to_polar_fcu(p: &Vector3<f32>, origin: &Vector3<f32>) -> PolarDeg {
    let h = cartesian_to_polar_histogram(p, origin);
    wrap_polar(PolarDeg {
        e_deg: -h.e_deg,
        z_deg: -h.z_deg + 90.0,
        r_m: h.r_m,
    })
}

/// Cell of a polar point on a grid of `res_deg` degrees: wrap, `floor(angle/res + offset/res)`, clamp.
pub fn polar_to_index(p: PolarDeg, res_deg: i32) -> CellIndex {
    let w = wrap_polar(p);
    let res = res_deg as f32;
    let e = floor_f32(w.e_deg / res + 90.0 / res) as i32;
    let z = floor_f32(w.z_deg / res + 180.0 / res) as i32;
    CellIndex {
        e: e.clamp(0, 180 / res_deg - 1) as usize,
        z: z.clamp(0, 360 / res_deg - 1) as usize,
    }
}

/// Cell-centre direction of cell (`e`, `z`) with integer arithmetic (`res/2` is integer division, 3 for res 6).
pub fn index_to_polar(e: usize, z: usize, res_deg: i32, r_m: f32) -> PolarDeg {
    PolarDeg {
        e_deg: (e as i32 * res_deg + res_deg / 2 - 90) as f32,
        z_deg: (z as i32 * res_deg + res_deg / 2 - 180) as f32,
        r_m,
    }
}

/// Upper bound of the error of [`fast_atan2_deg`] in degrees (checked by a test; the polynomial's own bound is
/// about 6e-4 deg).
pub const FAST_ATAN2_MAX_ERR_DEG: f32 = 2e-3;

/// Approximate `atan2(y, x)` in degrees (Abramowitz-Stegun 4.4.49 polynomial). Only used to pick grid cells
/// quickly; callers fall back to the exact [`f32::atan2`] when the result is near a cell boundary, so the chosen
/// cells are exactly those of the exact formula.
#[inline]
pub fn fast_atan2_deg(y: f32, x: f32) -> f32 {
    // Branch-free (selects only) so loops over many points vectorise.
    let ax = x.abs();
    let ay = y.abs();
    let mx = ax.max(ay).max(f32::MIN_POSITIVE);
    let mn = ax.min(ay);
    let t = mn / mx;
    let t2 = t * t;
    let mut a = t * (0.999_866 + t2 * (-0.330_299_5 + t2 * (0.180_141 + t2 * (-0.085_133 + t2 * 0.020_835_1))));
    a = if ay > ax { std::f32::consts::FRAC_PI_2 - a } else { a };
    a = if x < 0.0 { std::f32::consts::PI - a } else { a };
    a = if y < 0.0 { -a } else { a };
    a * RAD_TO_DEG
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn idx(e: f32, z: f32, res: i32) -> (usize, usize) {
        let c = polar_to_index(PolarDeg::new(e, z, 0.0), res);
        (c.e, c.z)
    }

    #[test]
    fn known_angle_to_index_from_spec() {
        // docs/planner.md §15, AV test_common polarToHistogramIndex.
        assert_eq!(idx(0.0, 0.0, 3), (30, 60));
        assert_eq!(idx(34.0, 34.0, 3), (41, 71));
        assert_eq!(idx(0.0, 0.0, 12), (7, 15));
        assert_eq!(idx(34.0, 34.0, 12), (10, 17));
        assert_eq!(idx(90.0, 180.0, 12), (14, 0));
        assert_eq!(idx(-90.0, -180.0, 12), (0, 0));
        assert_eq!(idx(454.0, -160.0, 3), (58, 66));
        assert_eq!(idx(400.0, -270.0, 12), (10, 22));
        assert_eq!(idx(-90.0, -180.00001, 12), (0, 29));
    }

    #[test]
    fn known_azimuth_and_elevation_of_axes() {
        let o = Vector3::new(1.0, -2.0, 3.0);
        let az = |d: Vector3<f32>| cartesian_to_polar_histogram(&(o + d), &o).z_deg;
        assert_eq!(az(Vector3::new(1.0, 0.0, 0.0)), 90.0);
        assert_eq!(az(Vector3::new(0.0, 1.0, 0.0)), 0.0);
        assert_eq!(az(Vector3::new(0.0, -1.0, 0.0)), 180.0);
        assert_eq!(az(Vector3::new(-1.0, 0.0, 0.0)), -90.0);
        let up = cartesian_to_polar_histogram(&(o + Vector3::new(0.0, 0.0, 2.0)), &o);
        assert_eq!(up.e_deg, 90.0);
        assert_eq!(up.r_m, 2.0);
    }

    #[test]
    fn cell_centres_and_layout() {
        assert_eq!(index_to_polar(0, 0, ALPHA_RES, 1.0), PolarDeg::new(-87.0, -177.0, 1.0));
        assert_eq!(index_to_polar(29, 59, ALPHA_RES, 1.0), PolarDeg::new(87.0, 177.0, 1.0));
        // South at column 0, West at 15, North at 30, East at 45 (checklist item 2).
        assert_eq!(idx(0.0, -180.0, ALPHA_RES).1, 0);
        assert_eq!(idx(0.0, -90.0, ALPHA_RES).1, 15);
        assert_eq!(idx(0.0, 0.0, ALPHA_RES).1, 30);
        assert_eq!(idx(0.0, 90.0, ALPHA_RES).1, 45);
        assert_eq!(idx(-90.0, 0.0, ALPHA_RES).0, 0);
        assert_eq!(idx(90.0, 0.0, ALPHA_RES).0, 29);
    }

    #[test]
    fn wraps_match_spec() {
        assert_eq!(wrap_180(180.0), -180.0);
        assert_eq!(wrap_180(-180.0), -180.0);
        assert_eq!(wrap_180(190.0), -170.0);
        assert_eq!(wrap_180(-540.0), -180.0);
        let p = wrap_polar(PolarDeg::new(100.0, 30.0, 1.0));
        assert_eq!((p.e_deg, p.z_deg), (80.0, -150.0));
        let p = wrap_polar(PolarDeg::new(-100.0, -30.0, 1.0));
        assert_eq!((p.e_deg, p.z_deg), (-80.0, 150.0));
        assert_eq!(angle_difference(170.0, -170.0), -20.0);
        assert_eq!(angle_difference(-170.0, 170.0), 20.0);
        assert_eq!(angle_difference(180.0, 0.0), -180.0);
        assert!((wrap_pi(3.0 * std::f32::consts::PI) + std::f32::consts::PI).abs() < 1e-5);
    }

    #[test]
    fn fcu_polar_is_ccw_from_east_and_positive_down() {
        let o = Vector3::zeros();
        let east = cartesian_to_polar_fcu(&Vector3::new(1.0, 0.0, 0.0), &o);
        assert_eq!(east.z_deg, 0.0);
        let north = cartesian_to_polar_fcu(&Vector3::new(0.0, 1.0, 0.0), &o);
        assert_eq!(north.z_deg, 90.0);
        let below = cartesian_to_polar_fcu(&Vector3::new(1.0, 0.0, -1.0), &o);
        assert!((below.e_deg - 45.0).abs() < 1e-4);
    }

    #[test]
    fn fast_atan2_error_is_bounded() {
        let mut worst = 0.0f32;
        for i in 0..20_000 {
            let a = i as f32 * (std::f32::consts::TAU / 20_000.0) - std::f32::consts::PI;
            for r in [1e-3f32, 0.7, 13.0] {
                let (y, x) = (r * a.sin(), r * a.cos());
                worst = worst.max((fast_atan2_deg(y, x) - y.atan2(x) * RAD_TO_DEG).abs());
            }
        }
        assert!(worst < FAST_ATAN2_MAX_ERR_DEG, "worst error {worst}");
    }

    #[test]
    fn floor_matches_std() {
        for x in [
            0.0f32,
            -0.5,
            0.5,
            -1.0,
            1.0,
            -1e-30,
            2.5e7,
            -2.5e7,
            8_388_607.5,
            -8_388_607.5,
            f32::INFINITY,
        ] {
            assert_eq!(floor_f32(x), x.floor(), "{x}");
        }
        assert!(floor_f32(f32::NAN).is_nan());
    }

    proptest! {
        #[test]
        fn floor_matches_std_everywhere(x in proptest::num::f32::NORMAL | proptest::num::f32::SUBNORMAL | proptest::num::f32::ZERO) {
            prop_assert_eq!(floor_f32(x), x.floor());
        }

        #[test]
        fn wrap_180_range_and_congruence(a in -5000.0f32..5000.0) {
            let w = wrap_180(a);
            prop_assert!((-180.0..180.0).contains(&w));
            let k = (a - w) / 360.0;
            prop_assert!((k - k.round()).abs() < 1e-3);
        }

        #[test]
        fn wrap_polar_is_in_range(e in -1000.0f32..1000.0, z in -1000.0f32..1000.0) {
            let p = wrap_polar(PolarDeg::new(e, z, 1.0));
            prop_assert!((-90.0..=90.0).contains(&p.e_deg));
            prop_assert!((-180.0..=180.0).contains(&p.z_deg));
        }

        #[test]
        fn index_polar_index_round_trip(e in 0usize..GRID_E, z in 0usize..GRID_Z) {
            let c = polar_to_index(index_to_polar(e, z, ALPHA_RES, 1.0), ALPHA_RES);
            prop_assert_eq!(c, CellIndex { e, z });
        }

        #[test]
        fn polar_cartesian_round_trip(e in -89.0f32..89.0, z in -179.0f32..179.0, r in 0.5f32..20.0) {
            let o = Vector3::new(3.0, -4.0, 2.0);
            let p = cartesian_to_polar_histogram(&polar_histogram_to_cartesian(&PolarDeg::new(e, z, r), &o), &o);
            prop_assert!((p.e_deg - e).abs() < 1e-2);
            prop_assert!((p.z_deg - z).abs() < 1e-2);
            prop_assert!((p.r_m - r).abs() < 1e-3);
        }

        #[test]
        fn angle_difference_is_signed_and_small(a in -720.0f32..720.0, b in -720.0f32..720.0) {
            let d = angle_difference(a, b);
            prop_assert!((-180.0..180.0).contains(&d));
            let k = (a - b - d) / 360.0;
            prop_assert!((k - k.round()).abs() < 1e-3);
        }
    }
}
