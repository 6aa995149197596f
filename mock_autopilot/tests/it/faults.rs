//! Every fault flag, exercised through the builder on ephemeral ports.

use std::time::Duration;

use mavlink::dialects::common::*;
use mock_autopilot::Faults;
use mock_autopilot::scenarios::mission2;

use crate::client::{Gcs, mock};

fn arm() -> [f32; 7] {
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
}

#[tokio::test]
async fn lossy_duplicating_slow_link_still_flies_mission2() {
    let faults = Faults {
        seed: 3,
        loss: 0.1,
        duplicate: 0.2,
        latency: Duration::from_millis(40),
        ..Default::default()
    };
    let m = mock(20.0, |b| b.faults(faults)).await;
    let gcs = Gcs::connect(&m).await;
    assert_eq!(
        gcs.upload(MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2()).await,
        Some(MavMissionResult::MAV_MISSION_ACCEPTED)
    );
    assert!(
        gcs.wait_prearm(Duration::from_secs(10)).await,
        "pre-arm checks pass once the estimator has settled"
    );
    assert_eq!(
        gcs.command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]).await,
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    let mut state = m.watch_state();
    let flown = tokio::time::timeout(Duration::from_secs(30), async {
        let mut armed = false;
        loop {
            if state.changed().await.is_err() {
                return false;
            }
            let s = *state.borrow();
            armed |= s.armed;
            if armed && !s.armed {
                return s.mission_finished;
            }
        }
    })
    .await;
    assert_eq!(flown, Ok(true));
    m.shutdown().await.expect("stop");
}

#[tokio::test]
async fn reject_mission_and_fail_arm() {
    let m = mock(5.0, |b| {
        b.reject_mission(Some(MavMissionResult::MAV_MISSION_NO_SPACE))
            .fail_arm(true)
    })
    .await;
    let gcs = Gcs::connect(&m).await;
    assert_eq!(
        gcs.upload(MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2()).await,
        Some(MavMissionResult::MAV_MISSION_NO_SPACE)
    );
    assert_eq!(
        gcs.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm()).await,
        Some(MavResult::MAV_RESULT_TEMPORARILY_REJECTED)
    );
    let text = gcs
        .wait(Duration::from_secs(2), |r| match r {
            MavMessage::STATUSTEXT(t) => t
                .text
                .to_str()
                .ok()
                .filter(|s| s.contains("Arming denied"))
                .map(str::to_string),
            _ => None,
        })
        .await;
    // The STATUSTEXT precedes the ACK, so it may already be consumed; the state is the proof.
    let _ = text;
    assert!(!m.state().armed);
    m.shutdown().await.expect("stop");
}

#[tokio::test]
async fn silence_after_stops_all_traffic() {
    let m = mock(10.0, |b| {
        b.faults(Faults {
            silence_after: Some(Duration::from_secs(2)),
            ..Default::default()
        })
    })
    .await;
    let gcs = Gcs::connect(&m).await;
    let first = gcs
        .request(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default()), 10, |r| {
            matches!(r, MavMessage::HEARTBEAT(_)).then_some(())
        })
        .await;
    assert!(first.is_some());
    // After 2 s simulated (0.2 s wall) nothing more arrives.
    let mut state = m.watch_state();
    let _ = tokio::time::timeout(
        Duration::from_secs(5),
        state.wait_for(|s| s.sim_time > Duration::from_secs(3)),
    )
    .await;
    while gcs.wait(Duration::from_millis(50), |_| Some(())).await.is_some() {}
    assert!(
        gcs.wait(Duration::from_millis(500), |_| Some(())).await.is_none(),
        "silent"
    );
    m.shutdown().await.expect("stop");
}

#[tokio::test]
async fn reboot_after_restarts_boot_time_and_disarms() {
    let m = mock(10.0, |b| {
        b.faults(Faults {
            reboot_after: Some(Duration::from_secs(5)),
            ..Default::default()
        })
    })
    .await;
    let gcs = Gcs::connect(&m).await;
    gcs.send(&MavMessage::HEARTBEAT(HEARTBEAT_DATA::default())).await;
    let mut last_boot_ms = 0u32;
    let rebooted = gcs
        .wait(Duration::from_secs(8), |r| {
            if let MavMessage::ATTITUDE(a) = r {
                if a.time_boot_ms + 1000 < last_boot_ms {
                    return Some((last_boot_ms, a.time_boot_ms));
                }
                last_boot_ms = a.time_boot_ms;
            }
            None
        })
        .await;
    let (before, after) = rebooted.expect("time_boot_ms restarted");
    assert!(
        before >= 2900 && after >= 3000 - 100 && after < before,
        "before {before} after {after}"
    );
    m.shutdown().await.expect("stop");
}
