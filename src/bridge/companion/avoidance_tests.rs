use super::*;

#[test]
fn mirrored_answers_warn_above_one_percent() {
    let s = CompanionStats::default();
    s.planned.store(700, Ordering::Relaxed);
    s.mirrored.store(1, Ordering::Relaxed);
    assert_eq!(s.warning(), None, "the first answer before any plan");
    s.mirrored.store(40, Ordering::Relaxed);
    assert!(s.warning().is_some_and(|w| w.starts_with("40 of 740")));
}

use crate::bridge::companion::steer::{MirrorSetpoint, Straight};
use crate::bridge::wire::pose::PoseNed;

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn request(p0: [f32; 3], p1: [f32; 3], cmd1: u16) -> TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
    let mut t = empty_trajectory(0, 3);
    (t.pos_x[0], t.pos_y[0], t.pos_z[0]) = (p0[0], p0[1], p0[2]);
    (t.pos_x[1], t.pos_y[1], t.pos_z[1]) = (p1[0], p1[1], p1[2]);
    t.command[1] = cmd1;
    t
}

fn flying() -> VehicleView {
    let mut v = VehicleView::default();
    v.armed = true;
    v.pose = Some(PoseNed {
        time_boot_ms: 1,
        pos_ned: [0.0, 0.0, -5.0],
        vel_ned: [0.0; 3],
        yaw_rad: Some(0.0),
    });
    v
}

#[test]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn mirrors_when_it_cannot_plan_and_goes_quiet_without_requests() {
    let mut c = Companion::default();
    let t0 = Duration::ZERO;
    assert!(
        c.answer(&flying(), &mut MirrorSetpoint, t0, 0).is_none(),
        "nobody asked"
    );
    c.on_request(&request([1.0, 2.0, -3.0], [10.0, 0.0, -5.0], u16::MAX), t0);
    let a = c.answer(&flying(), &mut MirrorSetpoint, t0, 7).unwrap();
    assert_eq!(
        (a.pos_x[0], a.pos_y[0], a.pos_z[0], a.valid_points),
        (1.0, 2.0, -3.0, 1)
    );
    assert_eq!(a.time_usec, 7);
    assert!(a.pos_x[1].is_nan());
    assert_eq!(c.mirrored, 1);
    assert!(
        c.answer(&flying(), &mut MirrorSetpoint, Duration::from_secs(2), 0)
            .is_none(),
        "stale request"
    );
}

/// A PX4 1.14 request: point 0 = PX4's setpoint (type `cmd0`), point 1 = current item (type `cmd1`).
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn px4(p0: [f32; 3], v0: [f32; 3], cmd0: u16, p1: [f32; 3], cmd1: u16) -> TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
    let mut t = request(p0, p1, cmd1);
    (t.vel_x[0], t.vel_y[0], t.vel_z[0]) = (v0[0], v0[1], v0[2]);
    t.command[0] = cmd0;
    t
}

/// PX4 1.14 landing at (50, 0): point 0 its land setpoint (z unset, 1.5 m/s down), point 1 the land item.
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn px4_land() -> TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
    let nan = f32::NAN;
    px4(
        [50.0, 0.0, nan],
        [nan, nan, 1.5],
        MAV_CMD_NAV_LAND,
        [50.0, 0.0, 0.0],
        MAV_CMD_NAV_LAND,
    )
}

const UNSET: u16 = u16::MAX;
const NAN3: [f32; 3] = [f32::NAN; 3];

#[test]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn goals_follow_px4_avoidance_through_takeoff_cruise_and_land() {
    let mut c = Companion::default();
    let t0 = Duration::ZERO;
    // Takeoff item: point 0 is the takeoff target, typed TAKEOFF.
    let tko = [0.0, 0.0, -10.0];
    c.on_request(&px4(tko, NAN3, MAV_CMD_NAV_TAKEOFF, tko, MAV_CMD_NAV_TAKEOFF), t0);
    assert_eq!((c.goal, c.nav), (Some([0.0, 0.0, -10.0]), Some(Nav::Takeoff)));
    // A plain waypoint as current item: it is the goal, whatever point 0 says.
    c.on_request(&px4([3.0, 0.0, -10.0], NAN3, UNSET, [30.0, 5.0, -10.0], UNSET), t0);
    assert_eq!(c.goal, Some([30.0, 5.0, -10.0]));
    assert_eq!(c.prev_goal, Some([0.0, 0.0, -10.0]));
    assert_eq!(c.nav, Some(Nav::Mission));
    // Move-to-land: PX4 makes the current item a plain position above the land point.
    c.on_request(&px4([50.0, 0.0, -10.0], NAN3, UNSET, [50.0, 0.0, -10.0], UNSET), t0);
    assert_eq!(c.goal, Some([50.0, 0.0, -10.0]));
    // Land: point 0 is PX4's land setpoint (z unset, descent speed); the flag comes from command[0].
    let land = px4_land();
    c.on_request(&land, t0);
    assert_eq!(c.nav, Some(Nav::Land));
    let g = c.goal.unwrap();
    assert_eq!((g[0], g[1]), (50.0, 0.0));
    assert!(g[2].is_nan(), "land goal has no height");
    let v = c.desired_vel.unwrap();
    assert!(v[0].is_nan() && v[2] == 1.5, "descent speed latched: {v:?}");
    // The same item again with another point 0: the goal stays (PX4-Avoidance updates on a new item only).
    let mut later = land.clone();
    later.vel_z[0] = 0.7;
    c.on_request(&later, t0);
    assert_eq!(c.desired_vel.unwrap()[2], 1.5);
}

#[test]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn landing_answer_is_a_descent_velocity_with_z_unset() {
    let mut c = Companion::default();
    let land = px4_land();
    c.on_request(&land, Duration::ZERO);
    let sp = SteerOutput {
        pos_ned: [50.0, 0.0, f64::NAN],
        vel_ned: [None, None, Some(1.5)],
        yaw_rad: None,
        yaw_rate_rad_s: None,
    };
    assert!(sp.is_complete());
    let a = c.answer_with(Some(sp), Duration::ZERO, 0).unwrap();
    assert_eq!((a.pos_x[0], a.vel_z[0]), (50.0, 1.5));
    assert!(a.pos_z[0].is_nan() && a.vel_x[0].is_nan());
    // Mirroring PX4's own land setpoint carries its velocity too.
    let m = c.answer_with(None, Duration::ZERO, 0).unwrap();
    assert!(m.pos_z[0].is_nan() && m.vel_z[0] == 1.5);
    assert!(!SteerOutput::position([0.0, 0.0, f64::NAN], None).is_complete());
}

#[test]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn the_answer_carries_the_yaw_rate_when_set_and_nan_when_not() {
    let mut c = Companion::default();
    c.on_request(&px4_land(), Duration::ZERO);
    let mut sp = SteerOutput::position([1.0, 2.0, -3.0], Some(0.5));
    let unset = c.answer_with(Some(sp), Duration::ZERO, 0).unwrap();
    assert!(unset.vel_yaw[0].is_nan() && unset.pos_yaw[0] == 0.5);
    sp.yaw_rate_rad_s = Some(0.0);
    assert_eq!(c.answer_with(Some(sp), Duration::ZERO, 0).unwrap().vel_yaw[0], 0.0);
}

#[test]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn plans_towards_the_current_waypoint() {
    let mut c = Companion::default();
    c.on_request(&request([1.0, 2.0, -3.0], [10.0, 0.0, -5.0], UNSET), Duration::ZERO);
    let a = c.answer(&flying(), &mut Straight, Duration::ZERO, 0).unwrap();
    assert_eq!((a.pos_x[0], a.pos_z[0]), (10.0, -5.0));
    assert_eq!(c.planned, 1);
}
