//! Reading and writing the points of `TRAJECTORY_REPRESENTATION_WAYPOINTS`, PX4's avoidance interface message:
//! five points whose unset axes are NaN.

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
use mavlink::dialects::common::TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA;

/// Position of point `i`; `None` unless every axis is set.
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
pub(super) fn point(t: &TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA, i: usize) -> Option<[f64; 3]> {
    let p = [t.pos_x[i], t.pos_y[i], t.pos_z[i]];
    p.iter().all(|v| v.is_finite()).then(|| p.map(f64::from))
}

/// Velocity of point `i`, unset axes as NaN; `None` if no axis is set.
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
pub(super) fn velocity_axes(t: &TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA, i: usize) -> Option<[f64; 3]> {
    let v = [t.vel_x[i], t.vel_y[i], t.vel_z[i]].map(f64::from);
    v.iter().any(|v| v.is_finite()).then_some(v)
}

/// A trajectory message with every point unset (NaN, command `u16::MAX`), as the interface expects for
/// points beyond `valid_points`.
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
pub fn empty_trajectory(time_usec: u64, valid_points: u8) -> TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
    let nan = [f32::NAN; 5];
    TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
        time_usec,
        pos_x: nan,
        pos_y: nan,
        pos_z: nan,
        vel_x: nan,
        vel_y: nan,
        vel_z: nan,
        acc_x: nan,
        acc_y: nan,
        acc_z: nan,
        pos_yaw: nan,
        vel_yaw: nan,
        command: [u16::MAX; 5],
        valid_points,
    }
}

/// Position of point `i` with NaN axes kept (PX4's land setpoint has z unset); `None` if x or y is unset.
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
pub(super) fn point_xy(t: &TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA, i: usize) -> Option<[f64; 3]> {
    let p = [t.pos_x[i], t.pos_y[i], t.pos_z[i]].map(f64::from);
    (p[0].is_finite() && p[1].is_finite()).then_some(p)
}
