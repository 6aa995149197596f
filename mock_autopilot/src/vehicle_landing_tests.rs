//! Landing with and without an avoidance companion: PX4's land detector decides, not the touchdown.

use std::time::Duration;

use mavlink::MavHeader;
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
use mavlink::dialects::common::{
    HEARTBEAT_DATA, MavCmd, MavLandedState, MavMessage, MavMissionType, MavState,
    TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA,
};

use super::*;
use crate::scenarios::{GCS, case_study_params, command, fly_until_disarmed, mission2, upload};

const DT: Duration = Duration::from_millis(4);

fn companion() -> MavHeader {
    MavHeader {
        system_id: 1,
        component_id: AVOIDANCE_COMPONENT_ID,
        sequence: 0,
    }
}

fn heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        system_status: MavState::MAV_STATE_ACTIVE,
        ..Default::default()
    })
}

/// What happened in a flight, in vehicle time since MISSION_START.
#[derive(Debug, Default)]
struct Log {
    /// First step on the ground (z = 0) after the takeoff.
    touchdown: Option<Duration>,
    landing_detected: Option<Duration>,
    disarmed: Option<Duration>,
    /// Requests whose point 0 is PX4's land setpoint (position z NaN, velocity z set).
    land_requests: usize,
    max_climb_m_s: f64,
    texts: Vec<String>,
}

/// Flies mission 2 with COM_OBS_AVOID 1 for `limit`, answering every request with `answer(request)` (None: no
/// answer). Stops at disarm.
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn fly_with_companion(
    limit: Duration,
    mut answer: impl FnMut(&TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA) -> Option<TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA>,
) -> (Vehicle, Log) {
    let mut v = Vehicle::new(VehicleConfig {
        params: case_study_params(),
        ..Default::default()
    });
    v.params.set("COM_OBS_AVOID", ParamValue::Int(1));
    upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
    v.handle(&companion(), &heartbeat());
    v.handle(&GCS, &command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]));
    assert!(v.state().armed, "armed with a healthy companion");
    let start = v.now();
    let mut log = Log::default();
    let mut k = 0u64;
    while v.now() - start < limit {
        v.step(DT);
        k += 1;
        if k.is_multiple_of(250) {
            v.handle(&companion(), &heartbeat());
        }
        let t = v.now() - start;
        let s = v.state();
        log.max_climb_m_s = log.max_climb_m_s.max(-s.vel_ned.z);
        if log.touchdown.is_none() && t > Duration::from_secs(10) && s.pos_ned.z >= 0.0 {
            log.touchdown = Some(t);
        }
        let out: Vec<MavMessage> = v.drain_outbox().collect();
        for m in &out {
            match m {
                MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(req) => {
                    if req.pos_z[0].is_nan() && req.vel_z[0].is_finite() {
                        log.land_requests += 1;
                    }
                    match answer(req) {
                        Some(a) => v.handle(&companion(), &MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(a)),
                        None => v.lockstep_release(),
                    }
                }
                MavMessage::STATUSTEXT(st) => {
                    let text = st.text.to_str().unwrap_or("").to_string();
                    if text == "Landing detected" {
                        log.landing_detected.get_or_insert(t);
                    }
                    log.texts.push(text);
                }
                _ => {}
            }
        }
        if log.touchdown.is_some() && !v.state().armed {
            log.disarmed = Some(t);
            break;
        }
    }
    (v, log)
}

/// The "cannot plan" answer: PX4's own point 0 back (for the land descent: position (x, y, NaN), velocity
/// (NaN, NaN, land speed), as PX4-Avoidance answers a landing).
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn mirror(req: &TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA) -> TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
    let mut a = req.clone();
    a.valid_points = 1;
    a
}

/// A companion that answers the land descent with a position setpoint at height `z` (NED) over the land point.
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn holding_at(
    z: f32,
) -> impl FnMut(&TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA) -> Option<TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA> {
    move |req| {
        let mut a = mirror(req);
        if req.pos_z[0].is_nan() {
            a.pos_z[0] = z;
            a.vel_z[0] = f32::NAN;
        }
        Some(a)
    }
}

#[test]
fn px4s_land_setpoint_lands_and_disarms_in_px4s_time_with_or_without_companion() {
    let (v, log) = fly_with_companion(Duration::from_secs(120), |r| Some(mirror(r)));
    assert!(
        log.land_requests > 10,
        "the descent asks with PX4's land setpoint: {log:?}"
    );
    let (touch, landed, disarmed) = (
        log.touchdown.expect("touched down"),
        log.landing_detected.expect("landing detected"),
        log.disarmed.expect("disarmed"),
    );
    // Land detector: thrust winds down (~0.1 s), then 3 x LNDMC_TRIG_TIME / 3; then COM_DISARM_LAND 2 s.
    let detect = (landed - touch).as_secs_f64();
    assert!(detect > 1.0 && detect < 1.4, "touchdown to landed {detect} s");
    let to_disarm = (disarmed - landed).as_secs_f64();
    assert!((to_disarm - 2.0).abs() < 0.01, "landed to disarmed {to_disarm} s");
    assert!(log.texts.iter().any(|t| t == "Disarmed by landing"), "{:?}", log.texts);
    assert!(v.state().mission_finished);

    // PX4 alone (COM_OBS_AVOID 0) lands on the same schedule.
    let mut v = Vehicle::new(VehicleConfig {
        params: case_study_params(),
        ..Default::default()
    });
    upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
    let mut touch = None;
    let mut landed = None;
    let end = fly_until_disarmed(&mut v, DT, Duration::from_secs(120), |v, m| {
        let t = v.now();
        if touch.is_none() && t > Duration::from_secs(10) && v.state().pos_ned.z >= 0.0 {
            touch = Some(t);
        }
        if matches!(&m, MavMessage::STATUSTEXT(s) if s.text.to_str().ok() == Some("Landing detected")) {
            landed = Some(t);
        }
    })
    .expect("disarmed");
    let (touch, landed) = (touch.expect("touchdown"), landed.expect("landing detected"));
    let detect = (landed - touch).as_secs_f64();
    assert!(detect > 1.0 && detect < 1.4, "touchdown to landed {detect} s");
    assert!(((end - landed).as_secs_f64() - 2.0).abs() < 0.01);
}

fn assert_never_lands(z: f32) {
    let (v, log) = fly_with_companion(Duration::from_secs(150), holding_at(z));
    assert!(log.land_requests > 10, "{log:?}");
    let s = v.state();
    assert!(s.armed && log.disarmed.is_none(), "never disarmed: {log:?}");
    assert_eq!(log.landing_detected, None, "{:?}", log.texts);
    assert_eq!(s.landed_state, MavLandedState::MAV_LANDED_STATE_LANDING);
    assert!(!s.mission_finished, "the land item waits for the land detector");
    assert!((s.pos_ned.z - f64::from(z)).abs() < 0.05, "held at {:?}", s.pos_ned);
    assert!(s.vel_ned.norm() < 0.05, "at rest: {s:?}");
    // At rest at the companion's height for a long time.
    let reached = v.nav.is_landing();
    assert!(reached, "still in the land descent");
}

#[test]
fn companion_holding_the_ground_with_a_position_never_lands() {
    // z = 0: the vehicle sits on the ground, but hover thrust and no commanded descent: no ground contact.
    assert_never_lands(0.0);
}

#[test]
fn companion_holding_just_above_the_ground_never_lands() {
    assert_never_lands(-0.3);
}

#[test]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn companion_positions_below_the_ground_or_velocity_descents_land() {
    // A position target under the ground keeps a descent commanded into it (as on PX4).
    let (_, log) = fly_with_companion(Duration::from_secs(150), holding_at(1.0));
    assert!(log.disarmed.is_some(), "{log:?}");
    // A plain velocity descent (position NaN) lands as well.
    let (_, log) = fly_with_companion(Duration::from_secs(150), |req| {
        let mut a = mirror(req);
        if req.pos_z[0].is_nan() {
            a.pos_x[0] = f32::NAN;
            a.pos_y[0] = f32::NAN;
            (a.vel_x[0], a.vel_y[0]) = (0.0, 0.0);
        }
        Some(a)
    });
    assert!(log.disarmed.is_some(), "{log:?}");
}

#[test]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn companion_answers_during_takeoff_keep_px4s_takeoff_speed() {
    // PX4-Avoidance answers the takeoff with a position at the goal altitude; a companion could answer with a
    // fast climb velocity. PX4 caps the climb at MPC_TKO_SPEED (FlightTaskAuto.cpp l. 827-829) either way.
    let tko = ParamTable::default().f64("MPC_TKO_SPEED");
    let (_, log) = fly_with_companion(Duration::from_secs(8), |req| {
        let mut a = mirror(req);
        if req.command[1] == MavCmd::MAV_CMD_NAV_TAKEOFF as u16 {
            a.pos_z[0] = req.pos_z[1];
        }
        Some(a)
    });
    assert!(
        log.max_climb_m_s > 0.9 * tko && log.max_climb_m_s <= tko + 1e-6,
        "{}",
        log.max_climb_m_s
    );
    let (_, log) = fly_with_companion(Duration::from_secs(8), |req| {
        let mut a = mirror(req);
        if req.command[1] == MavCmd::MAV_CMD_NAV_TAKEOFF as u16 {
            (a.pos_x[0], a.pos_y[0], a.pos_z[0]) = (f32::NAN, f32::NAN, f32::NAN);
            (a.vel_x[0], a.vel_y[0], a.vel_z[0]) = (0.0, 0.0, -5.0);
        }
        Some(a)
    });
    // Capped at the takeoff speed (plus the mock's velocity-loop overshoot), not the companion's 5 m/s.
    assert!(log.max_climb_m_s <= 1.1 * tko, "{}", log.max_climb_m_s);
    assert!(log.texts.iter().any(|t| t == "Takeoff detected"));
}
