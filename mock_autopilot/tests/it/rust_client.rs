//! rust-mavlink as the client, the way the bridge uses the mock.

use std::time::Duration;

use mavlink::dialects::common::*;
use mock_autopilot::FlightMode;
use mock_autopilot::scenarios::mission2;

use crate::client::{Gcs, mock};

#[tokio::test]
async fn mission2_over_udp_to_landing() {
    let m = mock(40.0, |b| b.param("NAV_ACC_RAD", mock_autopilot::ParamValue::Float(0.5))).await;
    let gcs = Gcs::connect(&m).await;
    let hb = gcs
        .request(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()), 10, |r| match r {
            MavMessage::HEARTBEAT(h) => Some(h.clone()),
            _ => None,
        })
        .await
        .expect("heartbeat");
    assert_eq!(hb.autopilot, MavAutopilot::MAV_AUTOPILOT_PX4);
    assert_eq!(hb.mavtype, MavType::MAV_TYPE_QUADROTOR);
    assert_eq!(FlightMode::from_custom_mode(hb.custom_mode), Some(FlightMode::Loiter));
    assert_eq!(
        gcs.upload(MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2()).await,
        Some(MavMissionResult::MAV_MISSION_ACCEPTED)
    );
    assert!(
        gcs.wait_prearm(Duration::from_secs(5)).await,
        "pre-arm checks pass once the estimator has settled"
    );
    assert_eq!(
        gcs.command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]).await,
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let mut reached = Vec::new();
    let mut positions = 0;
    let mut armed_seen = false;
    let done = gcs
        .wait(Duration::from_secs(20), |msg| {
            match msg {
                MavMessage::MISSION_ITEM_REACHED(r) if !reached.contains(&r.seq) => reached.push(r.seq),
                MavMessage::LOCAL_POSITION_NED(_) => positions += 1,
                MavMessage::HEARTBEAT(h) => {
                    let armed = h.base_mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                    armed_seen |= armed;
                    if armed_seen && !armed {
                        return Some(());
                    }
                }
                _ => {}
            }
            None
        })
        .await;
    assert!(done.is_some(), "disarmed after landing; reached {reached:?}");
    assert_eq!(reached, vec![0, 1, 2, 3]);
    let s = m.state();
    assert!((s.pos_ned.x - -12.36).abs() < 0.6 && (s.pos_ned.y - 0.13).abs() < 0.6);
    assert!(
        positions > 30 * 25,
        "LOCAL_POSITION_NED at >= 30 Hz simulated: {positions}"
    );
    m.shutdown().await.expect("clean stop");
}

#[tokio::test]
async fn params_commands_and_requests_like_px4() {
    let m = mock(1.0, |b| b).await;
    let gcs = Gcs::connect(&m).await;
    let set = MavMessage::PARAM_SET(PARAM_SET_DATA {
        param_value: f32::from_bits(1),
        target_system: 1,
        target_component: 1,
        param_id: "COM_OBS_AVOID".into(),
        param_type: MavParamType::MAV_PARAM_TYPE_INT32,
    });
    let v = gcs
        .request(&set, 10, |r| match r {
            MavMessage::PARAM_VALUE(p) if p.param_id.to_str().ok() == Some("COM_OBS_AVOID") => Some(p.clone()),
            _ => None,
        })
        .await
        .expect("PARAM_VALUE");
    assert_eq!(
        (v.param_type, v.param_value.to_bits()),
        (MavParamType::MAV_PARAM_TYPE_INT32, 1)
    );
    // Avoidance on and no companion: arming is refused, the mock carries on.
    assert_eq!(
        gcs.command(
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        )
        .await,
        Some(MavResult::MAV_RESULT_TEMPORARILY_REJECTED)
    );
    assert_eq!(
        gcs.command(MavCmd::MAV_CMD_DO_FLIGHTTERMINATION, [1.0; 7]).await,
        Some(MavResult::MAV_RESULT_UNSUPPORTED)
    );
    assert_eq!(
        gcs.command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]).await,
        Some(MavResult::MAV_RESULT_DENIED)
    );
    let req =
        mock_autopilot::scenarios::command(MavCmd::MAV_CMD_REQUEST_MESSAGE, [148.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    let ver = gcs
        .request(&req, 10, |r| match r {
            MavMessage::AUTOPILOT_VERSION(v) => Some(v.flight_sw_version),
            _ => None,
        })
        .await;
    assert_eq!(ver, Some(mock_autopilot::messages::FLIGHT_SW_VERSION));
    let req = mock_autopilot::scenarios::command(
        MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        [32.0, 10_000.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    assert!(
        gcs.request(&req, 10, |r| {
            matches!(r, MavMessage::COMMAND_ACK(a) if a.result == MavResult::MAV_RESULT_ACCEPTED).then_some(())
        })
        .await
        .is_some()
    );
    // At the 100 Hz just set: count over 0.5 s wall at speed 1.
    let mut n = 0;
    gcs.wait(Duration::from_millis(500), |r| {
        n += usize::from(matches!(r, MavMessage::LOCAL_POSITION_NED(_)));
        None::<()>
    })
    .await;
    assert!(
        n >= 35,
        "LOCAL_POSITION_NED after SET_MESSAGE_INTERVAL 100 Hz: {n} in 0.5 s"
    );
    m.shutdown().await.expect("clean stop");
}
