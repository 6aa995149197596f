use std::time::Duration;

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
