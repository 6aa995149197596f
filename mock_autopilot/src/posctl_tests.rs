use std::time::Duration;

use mavlink::dialects::common::{COMMAND_ACK_DATA, MANUAL_CONTROL_DATA, MavCmd, MavFrame, MavMessage, MavResult};

use super::*;
use crate::obstacles::{ObstacleWorld, SolidBox};
use crate::params::ParamValue;
use crate::range_scan::RangeSensor;
use crate::release::Px4Release;
use crate::scenarios::{GCS, command};
use crate::vehicle::VehicleConfig;

const DT: Duration = Duration::from_millis(4);

/// A wall across North at x 19..21, 40 m wide and 30 m high.
fn wall() -> SolidBox {
    SolidBox {
        x: 20.0,
        y: 0.0,
        l: 2.0,
        w: 40.0,
        r_deg: 0.0,
        bottom_m: 0.0,
        top_m: 30.0,
    }
}

/// A vehicle acting as PX4 v1.16.2, whose Position mode and Collision Prevention the mock models.
fn vehicle(params: &[(&str, ParamValue)]) -> Vehicle {
    vehicle_of(Px4Release::parse("1.16.2").unwrap(), params)
}

fn vehicle_of(release: Px4Release, params: &[(&str, ParamValue)]) -> Vehicle {
    Vehicle::new(VehicleConfig {
        params: params.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
        collision: Some(Box::new(ObstacleWorld::new(vec![wall()]))),
        release,
        ..Default::default()
    })
}

fn sticks(x: i16, y: i16) -> MavMessage {
    MavMessage::MANUAL_CONTROL(MANUAL_CONTROL_DATA {
        x,
        y,
        z: 500,
        target: 1,
        ..Default::default()
    })
}

/// What a run saw.
#[derive(Default)]
struct Seen {
    acks: Vec<(MavCmd, MavResult)>,
    texts: Vec<String>,
    echoes: usize,
    max_x: f64,
    max_y: f64,
}

/// Steps `secs`, sending `stick` every 40 ms (None: no sticks) and a 90-degree scan of the wall every 100 ms
/// when `sensor`.
fn run(v: &mut Vehicle, secs: f64, stick: Option<(i16, i16)>, sensor: bool, seen: &mut Seen) {
    let s = RangeSensor {
        fov_deg: 90.0,
        min_m: 0.2,
        max_m: 30.0,
    };
    let end = v.now() + Duration::from_secs_f64(secs);
    let mut k = 0u64;
    while v.now() < end {
        if let Some((x, y)) = stick
            && k.is_multiple_of(10)
        {
            v.handle(&GCS, &sticks(x, y));
        }
        if sensor && k.is_multiple_of(25) {
            let scan = s.scan(&[wall()], &v.body.pos_ned, v.body.yaw_rad, 0);
            v.handle(&GCS, &MavMessage::OBSTACLE_DISTANCE(scan));
        }
        v.step(DT);
        k += 1;
        seen.max_x = seen.max_x.max(v.body.pos_ned.x);
        seen.max_y = seen.max_y.max(v.body.pos_ned.y.abs());
        for m in v.drain_outbox() {
            match m {
                MavMessage::COMMAND_ACK(COMMAND_ACK_DATA { command, result, .. }) => seen.acks.push((command, result)),
                MavMessage::STATUSTEXT(t) => seen.texts.push(t.text.to_str().unwrap_or("").to_string()),
                MavMessage::OBSTACLE_DISTANCE(o) if o.frame == MavFrame::MAV_FRAME_BODY_FRD => seen.echoes += 1,
                _ => {}
            }
        }
    }
}

fn posctl() -> MavMessage {
    command(MavCmd::MAV_CMD_DO_SET_MODE, [1.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0])
}

/// Armed, taken off to 2.5 m and in Position mode with centred sticks (and the wall sensor when `sensor`).
fn airborne_in_posctl(v: &mut Vehicle, sensor: bool) -> Seen {
    let mut seen = Seen::default();
    v.handle(
        &GCS,
        &command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
    );
    v.handle(
        &GCS,
        &command(MavCmd::MAV_CMD_NAV_TAKEOFF, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, f32::NAN]),
    );
    run(v, 8.0, None, false, &mut seen);
    v.handle(&GCS, &posctl());
    run(v, 0.2, Some((0, 0)), sensor, &mut seen);
    v.handle(&GCS, &posctl());
    run(v, 1.0, Some((0, 0)), sensor, &mut seen);
    assert_eq!(v.state().mode, FlightMode::Posctl, "{:?}", seen.texts);
    seen
}

fn cp(dist: f32) -> [(&'static str, ParamValue); 1] {
    [("CP_DIST", ParamValue::Float(dist))]
}

#[test]
fn position_mode_needs_sticks_when_armed_then_flies_them() {
    let mut v = vehicle(&[]);
    let seen = airborne_in_posctl(&mut v, false);
    let set_mode: Vec<MavResult> = seen
        .acks
        .iter()
        .filter(|(c, _)| *c == MavCmd::MAV_CMD_DO_SET_MODE)
        .map(|(_, r)| *r)
        .collect();
    assert_eq!(
        set_mode,
        vec![
            MavResult::MAV_RESULT_TEMPORARILY_REJECTED,
            MavResult::MAV_RESULT_ACCEPTED
        ]
    );
    assert!(
        seen.texts
            .iter()
            .any(|t| t.contains("Switching to Position is currently not possible"))
    );
    let z = v.body.pos_ned.z;
    let mut seen = Seen::default();
    run(&mut v, 2.5, Some((1000, 0)), false, &mut seen);
    assert!(v.body.vel_ned.x > 4.0 && !v.state().crashed, "{:?}", v.body.vel_ned);
    assert!((v.body.pos_ned.z - z).abs() < 0.2, "altitude held");
    assert_eq!(seen.echoes, 0, "no map echoed while Collision Prevention is off");
}

#[test]
fn collision_prevention_stops_before_the_wall_and_echoes_its_map() {
    let mut v = vehicle(&cp(3.0));
    let mut seen = airborne_in_posctl(&mut v, true);
    run(&mut v, 20.0, Some((1000, 0)), true, &mut seen);
    let gap = 19.0 - seen.max_x;
    assert!(
        gap > 2.0 && gap < 3.5,
        "closest {gap:.2} m from the wall with CP_DIST 3"
    );
    assert!(!v.state().crashed);
    assert!(v.body.vel_ned.xy().norm() < 0.3, "stopped: {:?}", v.body.vel_ned);
    assert!(
        (200..=215).contains(&seen.echoes),
        "10 Hz echo over 21.2 s: {}",
        seen.echoes
    );
}

#[test]
fn cp_dist_minus_one_flies_into_the_wall() {
    let mut v = vehicle(&cp(-1.0));
    let mut seen = airborne_in_posctl(&mut v, true);
    run(&mut v, 20.0, Some((1000, 0)), true, &mut seen);
    assert!(v.state().crashed, "flew to x {:.1}", seen.max_x);
}

#[test]
fn v1_14_collision_prevention_ignores_the_acceleration_based_position_mode() {
    // PX4 v1.14 SIH at its default MPC_POS_MODE 4 flew a CP_DIST 2 test into a box; with 3 it held back.
    let mut v = vehicle_of(Px4Release::V1_14_0, &cp(3.0));
    let mut seen = airborne_in_posctl(&mut v, true);
    run(&mut v, 20.0, Some((1000, 0)), true, &mut seen);
    assert!(v.state().crashed, "flew to x {:.1}", seen.max_x);
    assert_eq!(seen.echoes, 0, "no map echoed while Collision Prevention is idle");
    let mut params = cp(3.0).to_vec();
    params.push(("MPC_POS_MODE", ParamValue::Int(3)));
    let mut v = vehicle_of(Px4Release::V1_14_0, &params);
    let mut seen = airborne_in_posctl(&mut v, true);
    run(&mut v, 20.0, Some((1000, 0)), true, &mut seen);
    assert!(
        !v.state().crashed && 19.0 - seen.max_x > 2.0,
        "flew to x {:.1}",
        seen.max_x
    );
}

#[test]
fn without_data_nothing_moves_then_hold() {
    let mut v = vehicle(&cp(3.0));
    let mut seen = airborne_in_posctl(&mut v, false);
    let start = v.body.pos_ned;
    run(&mut v, 3.0, Some((1000, 0)), false, &mut seen);
    assert!(
        (v.body.pos_ned - start).xy().norm() < 0.1,
        "moved {:?}",
        v.body.pos_ned - start
    );
    run(&mut v, 3.0, Some((1000, 0)), false, &mut seen);
    assert_eq!(v.state().mode, FlightMode::Loiter, "{:?}", seen.texts);
}

#[test]
fn unknown_sectors_are_closed_unless_cp_go_no_data() {
    // The sensor sees 90 degrees ahead; the right stick points where it never looked.
    let mut v = vehicle(&cp(3.0));
    let mut seen = airborne_in_posctl(&mut v, true);
    run(&mut v, 4.0, Some((0, 1000)), true, &mut seen);
    assert!(seen.max_y < 0.2, "moved {:.2} m right", seen.max_y);
    let mut v = vehicle(&[
        ("CP_DIST", ParamValue::Float(3.0)),
        ("CP_GO_NO_DATA", ParamValue::Int(1)),
    ]);
    let mut seen = airborne_in_posctl(&mut v, true);
    run(&mut v, 4.0, Some((0, 1000)), true, &mut seen);
    assert!(seen.max_y > 5.0, "moved {:.2} m right", seen.max_y);
}

#[test]
fn lost_sticks_hold_then_return() {
    let mut v = vehicle(&[]);
    let mut seen = airborne_in_posctl(&mut v, false);
    run(&mut v, 0.7, None, false, &mut seen);
    assert_eq!(v.state().mode, FlightMode::Loiter);
    run(&mut v, 4.0, None, false, &mut seen);
    assert_eq!(v.state().mode, FlightMode::Loiter);
    run(&mut v, 1.5, None, false, &mut seen);
    assert_eq!(v.state().mode, FlightMode::Rtl, "{:?}", seen.texts);
    assert!(seen.texts.iter().any(|t| t.contains("manual control lost, Return")));
    // Sticks back during the hold: back to Position mode.
    let mut v = vehicle(&[]);
    let mut seen = airborne_in_posctl(&mut v, false);
    run(&mut v, 1.0, None, false, &mut seen);
    assert_eq!(
        v.system_status(),
        mavlink::dialects::common::MavState::MAV_STATE_CRITICAL
    );
    run(&mut v, 0.5, Some((0, 0)), false, &mut seen);
    assert_eq!(v.state().mode, FlightMode::Posctl);
    assert_eq!(v.system_status(), mavlink::dialects::common::MavState::MAV_STATE_ACTIVE);
}

#[test]
fn a_mission_flown_without_sticks_never_sees_the_loss_failsafe() {
    let mut v = vehicle(&[]);
    let mut seen = Seen::default();
    v.handle(
        &GCS,
        &command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
    );
    v.handle(
        &GCS,
        &command(MavCmd::MAV_CMD_NAV_TAKEOFF, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, f32::NAN]),
    );
    run(&mut v, 10.0, None, false, &mut seen);
    assert!(
        !seen.texts.iter().any(|t| t.contains("manual control")),
        "{:?}",
        seen.texts
    );
}

#[test]
fn lockstep_waits_for_the_next_stick_and_goes_on_when_released() {
    let mut v = vehicle(&[]);
    let mut seen = airborne_in_posctl(&mut v, false);
    assert!(!v.lockstep_blocked(), "sticks are fresh");
    let mut waited = Duration::ZERO;
    while !v.lockstep_blocked() && waited < Duration::from_secs(1) {
        v.step(DT);
        waited += DT;
    }
    assert!(
        waited > crate::stick_lockstep::STICK_LOCKSTEP_AGE - Duration::from_millis(40)
            && waited <= crate::stick_lockstep::STICK_LOCKSTEP_AGE,
        "blocked after {waited:?} without sticks"
    );
    v.handle(&GCS, &sticks(0, 0));
    assert!(!v.lockstep_blocked(), "a stick releases the clock");
    run(&mut v, 0.2, None, false, &mut seen);
    assert!(v.lockstep_blocked());
    v.lockstep_release();
    assert!(!v.lockstep_blocked(), "released: no more waits");
    run(&mut v, 0.2, None, false, &mut seen);
    assert!(!v.lockstep_blocked(), "until sticks come back");
    assert!(
        seen.texts.iter().any(|t| t.contains("no sticks in time")),
        "{:?}",
        seen.texts
    );
    v.handle(&GCS, &sticks(0, 0));
    run(&mut v, 0.2, None, false, &mut seen);
    assert!(v.lockstep_blocked(), "waits again once sticks came back");
}

#[test]
fn lockstep_keeps_the_sticks_fresh_for_arming_in_position_mode() {
    let mut v = vehicle(&[]);
    let mut seen = Seen::default();
    run(&mut v, 8.0, Some((0, 0)), false, &mut seen);
    assert!(!v.lockstep_blocked(), "disarmed outside Position mode: no wait");
    v.handle(&GCS, &posctl());
    run(&mut v, 0.2, Some((0, 0)), false, &mut seen);
    assert_eq!(v.state().mode, FlightMode::Posctl, "{:?}", seen.texts);
    run(&mut v, 0.2, None, false, &mut seen);
    assert!(
        v.lockstep_blocked(),
        "disarmed in Position mode, the sticks are waited for"
    );
    v.handle(&GCS, &sticks(0, 0));
    assert!(!v.lockstep_blocked());
}
