//! Garbage in never crashes the mock: random bytes, bad CRCs, unknown ids, out-of-range items.

use std::net::UdpSocket;
use std::time::Duration;

use mavlink::MavHeader;
use mavlink::dialects::common::*;
use mock_autopilot::scenarios::{command, item};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::client::{Gcs, mock};

fn frame(msg: &MavMessage) -> Vec<u8> {
    let mut buf = Vec::new();
    let h = MavHeader {
        system_id: 255,
        component_id: 190,
        sequence: 0,
    };
    mavlink::write_v2_msg(&mut buf, h, msg).expect("serialize");
    buf
}

#[tokio::test]
async fn garbage_is_ignored_and_the_mock_keeps_answering() {
    let m = mock(5.0, |b| b).await;
    let addr = m.local_addr().expect("addr");
    let raw = UdpSocket::bind("127.0.0.1:0").expect("bind");
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    for _ in 0..300 {
        let n = rng.random_range(0..600);
        let bytes: Vec<u8> = (0..n).map(|_| rng.random()).collect();
        raw.send_to(&bytes, addr).expect("send");
    }
    // Valid-looking frames with a broken CRC, and a v2 frame with an unknown message id.
    let mut bad = frame(&MavMessage::PARAM_REQUEST_LIST(PARAM_REQUEST_LIST_DATA {
        target_system: 1,
        target_component: 1,
    }));
    let last = bad.len() - 1;
    bad[last] ^= 0x5A;
    raw.send_to(&bad, addr).expect("send");
    let mut unknown = frame(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()));
    unknown[7] = 0x77;
    unknown[8] = 0x77;
    unknown[9] = 0x07;
    raw.send_to(&unknown, addr).expect("send");
    // Truncated frame: header only.
    raw.send_to(&frame(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()))[..6], addr)
        .expect("send");

    let gcs = Gcs::connect(&m).await;
    // Out-of-range and nonsense protocol content.
    let mut far = item(0, MavCmd::MAV_CMD_NAV_WAYPOINT, 95.0, 8.0, 10.0);
    far.x = i32::MAX;
    assert_eq!(
        gcs.upload(MavMissionType::MAV_MISSION_TYPE_MISSION, &[far]).await,
        Some(MavMissionResult::MAV_MISSION_INVALID_PARAM5_X)
    );
    let mut nan = item(0, MavCmd::MAV_CMD_NAV_WAYPOINT, 47.4, 8.5, f32::NAN);
    nan.param1 = f32::NAN;
    assert!(
        matches!(gcs.upload(MavMissionType::MAV_MISSION_TYPE_MISSION, &[nan]).await, Some(code) if code != MavMissionResult::MAV_MISSION_ACCEPTED)
    );
    for cmd in [
        MavCmd::MAV_CMD_NAV_TAKEOFF,
        MavCmd::MAV_CMD_DO_SET_MODE,
        MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL,
        MavCmd::MAV_CMD_REQUEST_MESSAGE,
        MavCmd::MAV_CMD_MISSION_START,
    ] {
        gcs.send(&command(
            cmd,
            [f32::NAN, f32::INFINITY, -1e30, 0.0, f32::NAN, 1e30, f32::NEG_INFINITY],
        ))
        .await;
    }
    gcs.send(&MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
        seq: 65535,
        target_system: 1,
        target_component: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_ALL,
    }))
    .await;
    gcs.send(&MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: 65535,
        target_system: 1,
        target_component: 1,
        mission_type: MavMissionType::MAV_MISSION_TYPE_FENCE,
        opaque_id: 0,
    }))
    .await;
    gcs.send(&MavMessage::SET_POSITION_TARGET_LOCAL_NED(
        SET_POSITION_TARGET_LOCAL_NED_DATA {
            x: f32::NAN,
            vx: f32::INFINITY,
            ..Default::default()
        },
    ))
    .await;
    gcs.send(&MavMessage::PARAM_SET(PARAM_SET_DATA {
        param_value: f32::NAN,
        target_system: 1,
        target_component: 1,
        param_id: "MPC_XY_CRUISE".into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    }))
    .await;

    // Still alive and sane.
    let v = gcs
        .request(
            &MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
                param_index: -1,
                target_system: 1,
                target_component: 1,
                param_id: "MPC_XY_CRUISE".into(),
            }),
            10,
            |r| match r {
                MavMessage::PARAM_VALUE(p) if p.param_id.to_str().ok() == Some("MPC_XY_CRUISE") => Some(p.param_value),
                _ => None,
            },
        )
        .await;
    assert_eq!(v, Some(5.0));
    assert!(
        gcs.wait(Duration::from_secs(3), |r| matches!(r, MavMessage::HEARTBEAT(_))
            .then_some(()))
            .await
            .is_some()
    );
    assert!(!m.state().armed);
    m.shutdown().await.expect("clean stop");
}
