use std::time::Duration;

use mavlink::MavHeader;
use mavlink::dialects::common::{MavLandedState, MavMessage, MavMissionResult, MavMissionType};

use super::*;
use crate::scenarios::{case_study_params, fly_until_disarmed, mission2, upload};

const DT: Duration = Duration::from_millis(4);

fn vehicle() -> Vehicle {
    Vehicle::new(VehicleConfig {
        params: case_study_params(),
        ..Default::default()
    })
}

#[test]
fn mission2_flies_to_landing_and_disarms() {
    let mut v = vehicle();
    assert_eq!(
        upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2()),
        Some(MavMissionResult::MAV_MISSION_ACCEPTED)
    );
    let mut reached = Vec::new();
    let mut landed_states = Vec::new();
    let mut max_h_speed = 0.0f64;
    let mut texts = Vec::new();
    let t = fly_until_disarmed(&mut v, DT, Duration::from_secs(200), |v, m| {
        max_h_speed = max_h_speed.max(v.state().vel_ned.xy().norm());
        match m {
            MavMessage::MISSION_ITEM_REACHED(r) if reached.last() != Some(&r.seq) => reached.push(r.seq),
            MavMessage::EXTENDED_SYS_STATE(e) if landed_states.last() != Some(&e.landed_state) => {
                landed_states.push(e.landed_state)
            }
            MavMessage::STATUSTEXT(s) => texts.push(s.text.to_str().unwrap_or("").to_string()),
            _ => {}
        }
    })
    .expect("disarmed after landing");
    assert_eq!(reached, vec![0, 1, 2, 3]);
    use MavLandedState::*;
    assert_eq!(
        landed_states,
        vec![
            MAV_LANDED_STATE_ON_GROUND,
            MAV_LANDED_STATE_TAKEOFF,
            MAV_LANDED_STATE_IN_AIR,
            MAV_LANDED_STATE_LANDING,
            MAV_LANDED_STATE_ON_GROUND
        ]
    );
    let p = v.state().pos_ned;
    assert!(
        (p.x - -12.36).abs() < 0.6 && (p.y - 0.13).abs() < 0.6 && p.z == 0.0,
        "landed at {p:?}"
    );
    assert!(max_h_speed <= 5.0 + 1e-6);
    assert!(
        t > Duration::from_secs(20) && t < Duration::from_secs(90),
        "flight took {t:?}"
    );
    for want in [
        "Armed by external command",
        "Takeoff detected",
        "Landing detected",
        "Disarmed by landing",
    ] {
        assert!(texts.iter().any(|t| t == want), "missing {want:?} in {texts:?}");
    }
    assert!(v.state().mission_finished);
}

#[test]
fn same_inputs_give_identical_flights() {
    let run = || {
        let mut v = vehicle();
        upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
        let mut trace = Vec::new();
        fly_until_disarmed(&mut v, DT, Duration::from_secs(200), |_, m| {
            if let MavMessage::LOCAL_POSITION_NED(p) = m {
                trace.push((p.x.to_bits(), p.y.to_bits(), p.z.to_bits()));
            }
        });
        trace
    };
    let a = run();
    assert!(a.len() > 100);
    assert_eq!(a, run());
}

/// The horizontal track of `flights` mission-2 flights in a row on one vehicle with `tuning` and `seed`.
fn gusty_tracks(tuning: Tuning, seed: u64, flights: usize) -> Vec<Vec<(f32, f32)>> {
    let mut v = Vehicle::new(VehicleConfig {
        params: case_study_params(),
        tuning,
        seed,
        ..Default::default()
    });
    upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
    (0..flights)
        .map(|_| {
            let mut track = Vec::new();
            fly_until_disarmed(&mut v, DT, Duration::from_secs(200), |_, m| {
                if let MavMessage::LOCAL_POSITION_NED(p) = m {
                    track.push((p.x, p.y));
                }
            })
            .expect("each flight lands");
            track
        })
        .collect()
}

#[test]
fn gusts_scatter_each_flight_and_repeat_for_the_same_seed() {
    let gusty = Tuning {
        gust_acc_m_s2: 0.5,
        ..Tuning::default()
    };
    let a = gusty_tracks(gusty, 3, 2);
    assert_eq!(a, gusty_tracks(gusty, 3, 2), "same seed, same flights, bit for bit");
    assert_ne!(a[0], a[1], "each arming draws new gusts");
    assert_ne!(a[0], gusty_tracks(gusty, 4, 1)[0], "another seed, other gusts");
    // Calm: the seed changes nothing.
    let calm = gusty_tracks(Tuning::default(), 3, 2);
    assert_eq!(calm[0], gusty_tracks(Tuning::default(), 9, 1)[0]);
    let end = |t: &Vec<(f32, f32)>| t.last().copied().unwrap_or_default();
    // Gusts move the vehicle off the calm track by a bounded amount: it still flies the mission.
    let off = a[0]
        .iter()
        .zip(&calm[0])
        .map(|(p, q)| f64::from((p.0 - q.0).hypot(p.1 - q.1)))
        .fold(0.0, f64::max);
    assert!(off > 0.05 && off < 5.0, "largest offset from the calm track {off} m");
    let (e, c) = (end(&a[0]), end(&calm[0]));
    assert!(
        (e.0 - c.0).hypot(e.1 - c.1) < 1.0,
        "lands near the calm landing: {e:?} vs {c:?}"
    );
}

fn header(component_id: u8) -> MavHeader {
    MavHeader {
        system_id: 1,
        component_id,
        sequence: 0,
    }
}

fn texts_of(msgs: &[MavMessage]) -> Vec<String> {
    msgs.iter()
        .filter_map(|m| match m {
            MavMessage::STATUSTEXT(s) => s.text.to_str().ok().map(str::to_string),
            _ => None,
        })
        .collect()
}

#[test]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn avoidance_companion_steers_and_its_silence_holds() {
    use mavlink::dialects::common::{HEARTBEAT_DATA, MavState};
    let mut v = vehicle();
    v.params.set("COM_OBS_AVOID", ParamValue::Int(1));
    upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
    // No companion: arming (via MISSION_START) is refused.
    v.handle(
        &crate::scenarios::GCS,
        &crate::scenarios::command(mavlink::dialects::common::MavCmd::MAV_CMD_MISSION_START, [0.0; 7]),
    );
    assert!(!v.state().armed);
    assert!(
        texts_of(&v.drain_outbox().collect::<Vec<_>>())
            .iter()
            .any(|t| t.contains("Avoidance system not ready"))
    );
    let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        system_status: MavState::MAV_STATE_ACTIVE,
        ..Default::default()
    });
    v.handle(&header(196), &hb);
    // A mirroring companion answering every request flies the mission like PX4 alone would.
    let mut requests = 0;
    let mut answering = true;
    let mut all = Vec::new();
    let mut held_at = None;
    v.handle(
        &crate::scenarios::GCS,
        &crate::scenarios::command(mavlink::dialects::common::MavCmd::MAV_CMD_MISSION_START, [0.0; 7]),
    );
    for k in 0..40_000 {
        v.step(DT);
        if k % 250 == 0 {
            v.handle(&header(196), &hb);
        }
        let out: Vec<MavMessage> = v.drain_outbox().collect();
        for m in &out {
            if let MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(t) = m {
                requests += 1;
                assert_eq!(t.valid_points, 3);
                assert!(
                    v.lockstep_blocked(),
                    "a lockstep runner waits for this request's answer"
                );
                if answering {
                    let mut a = t.clone();
                    a.valid_points = 1;
                    v.handle(&header(196), &MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(a));
                    assert!(!v.lockstep_blocked(), "answered");
                } else {
                    v.lockstep_release();
                    assert!(!v.lockstep_blocked(), "released after the runner's wall-time bound");
                    // Said aloud: from here the flight depends on the machine's load.
                    let said = v.drain_outbox().any(|m| {
                        matches!(&m, MavMessage::STATUSTEXT(t) if t.text.to_str().is_ok_and(|s| s.starts_with("Lockstep")))
                    });
                    assert!(said, "a released lockstep wait is reported");
                }
            }
        }
        all.extend(out);
        // Halfway to the waypoint the companion goes quiet: the vehicle must hold there.
        if answering && v.state().pos_ned.y > 25.0 {
            answering = false;
            held_at = Some(v.now());
        }
        if let Some(t) = held_at
            && v.now() - t > Duration::from_secs(10)
        {
            break;
        }
    }
    let texts = texts_of(&all);
    assert!(texts.iter().any(|t| t == "Avoidance system timeout"), "{texts:?}");
    let s = v.state();
    assert!(s.armed && s.vel_ned.norm() < 0.2, "holding: {s:?}");
    assert!(
        s.pos_ned.y > 25.0 && s.pos_ned.y < 35.0,
        "held near where answers stopped: {:?}",
        s.pos_ned
    );
    // 5 Hz over the flight so far.
    let secs = v.now().as_secs_f64();
    assert!(
        (requests as f64) > 4.5 * (secs - 1.0),
        "{requests} requests in {secs} s"
    );
}

/// Mission 2 through an exclusion fence across its first leg (East 20-30 m) with `GF_ACTION = action`; returns
/// the vehicle, its STATUSTEXTs and the time it disarmed (None: still flying after 120 s).
fn fly_through_fence(action: i32) -> (Vehicle, Vec<String>, Option<Duration>) {
    use crate::scenarios::item;
    use mavlink::dialects::common::MavCmd;
    let mut v = vehicle();
    v.params.set("GF_ACTION", ParamValue::Int(action));
    upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
    let proj = v.proj;
    let ex = MavCmd::MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION;
    let fence: Vec<_> = [(-20.0, 20.0), (-20.0, 30.0), (20.0, 30.0), (20.0, 20.0)]
        .iter()
        .enumerate()
        .map(|(k, &(n, e))| {
            let (lat, lon) = proj.unproject(n, e);
            let mut it = item(k as u16, ex, lat, lon, 0.0);
            it.param1 = 4.0;
            it
        })
        .collect();
    assert_eq!(
        upload(&mut v, MavMissionType::MAV_MISSION_TYPE_FENCE, &fence),
        Some(MavMissionResult::MAV_MISSION_ACCEPTED)
    );
    let mut texts = Vec::new();
    let end = fly_until_disarmed(&mut v, DT, Duration::from_secs(120), |_, m| {
        if let MavMessage::STATUSTEXT(s) = m {
            texts.push(s.text.to_str().unwrap_or("").to_string());
        }
    });
    (v, texts, end)
}

/// PX4 v1.14's two texts on a breach, in order, once per entry into the fence.
fn assert_breach_texts(texts: &[String], entries: usize) {
    let breach = [crate::safety::GEOFENCE_VIOLATION, crate::safety::FAILSAFE_ACTIVATED];
    let pairs = texts.windows(2).filter(|w| *w == breach).count();
    assert_eq!(pairs, entries, "PX4 v1.14's texts per entry, in order: {texts:?}");
}

#[test]
fn exclusion_fence_breach_holds_with_px4_text() {
    let (v, texts, end) = fly_through_fence(2);
    assert!(end.is_none(), "GF_ACTION 2 holds in the air, no landing");
    assert_breach_texts(&texts, 1);
    assert_eq!(v.state().mode, FlightMode::Loiter);
    assert!(v.state().pos_ned.y > 19.0 && v.state().pos_ned.y < 25.0);
}

/// What the bridge sets (GF_ACTION 1): PX4 v1.14 SIH says "Preflight Fail: Geofence violation" and "Failsafe
/// activated" and flies the mission on to its land point (15 of 15 mission-mode flights of mission 3).
#[test]
fn exclusion_fence_breach_with_warning_only_flies_on_with_px4_text() {
    let (v, texts, end) = fly_through_fence(1);
    assert!(end.is_some(), "the mission ends landed and disarmed: {texts:?}");
    // Out and back across the fence: one pair of texts per entry.
    assert_breach_texts(&texts, 2);
    assert!(texts.iter().any(|t| t == "Mission finished, landed\t"), "{texts:?}");
    let land = mission2()
        .last()
        .map(|i| v.proj.project(f64::from(i.x) * 1e-7, f64::from(i.y) * 1e-7))
        .expect("land item");
    let p = v.state().pos_ned;
    assert!(
        (p.x - land.0).hypot(p.y - land.1) < 1.0,
        "landed at {p:?}, land item {land:?}"
    );
}

#[test]
fn collision_crashes_disarms_and_grounds() {
    struct Wall;
    impl CollisionWorld for Wall {
        fn collision(&self, p: &Ned) -> Option<String> {
            (p.y > 30.0 && p.y < 32.0 && p.z > -20.0).then(|| "collided with obstacle 0".to_string())
        }
    }
    let mut v = Vehicle::new(VehicleConfig {
        params: case_study_params(),
        collision: Some(Box::new(Wall)),
        ..Default::default()
    });
    upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
    let mut texts = Vec::new();
    let t = fly_until_disarmed(&mut v, DT, Duration::from_secs(100), |_, m| {
        if let MavMessage::STATUSTEXT(s) = m {
            texts.push(s.text.to_str().unwrap_or("").to_string());
        }
    });
    assert!(t.is_some());
    let s = v.state();
    assert!(
        s.crashed && !s.armed && s.pos_ned.z == 0.0 && s.landed_state == MavLandedState::MAV_LANDED_STATE_ON_GROUND
    );
    assert!(
        texts.iter().any(|t| t == "Crash detected: collided with obstacle 0"),
        "{texts:?}"
    );
}

#[test]
fn offboard_setpoints_fly_and_their_loss_triggers_failsafe() {
    use mavlink::dialects::common::{MavCmd, PositionTargetTypemask, SET_POSITION_TARGET_LOCAL_NED_DATA};
    let mut v = vehicle();
    let sp = MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
        x: 5.0,
        y: 0.0,
        z: -3.0,
        type_mask: PositionTargetTypemask::from_bits_truncate(0b1111_1111_1000),
        target_system: 1,
        target_component: 1,
        ..Default::default()
    });
    v.handle(&crate::scenarios::GCS, &sp);
    v.handle(
        &crate::scenarios::GCS,
        &crate::scenarios::command(MavCmd::MAV_CMD_DO_SET_MODE, [1.0, 6.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
    );
    v.handle(
        &crate::scenarios::GCS,
        &crate::scenarios::command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ),
    );
    assert_eq!((v.state().mode, v.state().armed), (FlightMode::Offboard, true));
    for k in 0..5000 {
        if k % 25 == 0 {
            v.handle(&crate::scenarios::GCS, &sp); // 10 Hz
        }
        v.step(DT);
    }
    assert!((v.state().pos_ned - Ned::new(5.0, 0.0, -3.0)).norm() < 0.1);
    v.drain_outbox().for_each(drop);
    for _ in 0..200 {
        v.step(DT);
    }
    assert_eq!(v.state().mode, FlightMode::Loiter, "COM_OF_LOSS_T 0.5 s then Hold");
    let texts = texts_of(&v.drain_outbox().collect::<Vec<_>>());
    assert!(texts.iter().any(|t| t.contains("no offboard setpoints")), "{texts:?}");
}
