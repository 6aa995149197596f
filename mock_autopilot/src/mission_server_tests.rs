use super::*;
use crate::scenarios::{item, mission2};
use mavlink::dialects::common::{MISSION_CLEAR_ALL_DATA, MISSION_REQUEST_LIST_DATA, MavCmd, MavFrame};

const GCS: (u8, u8) = (255, 190);
const MISSION: MavMissionType = MavMissionType::MAV_MISSION_TYPE_MISSION;

fn ms(v: u64) -> Duration {
    Duration::from_millis(v)
}

fn count(n: u16, ty: MavMissionType) -> MavMessage {
    MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: n,
        target_system: 1,
        target_component: 1,
        mission_type: ty,
        opaque_id: 0,
    })
}

fn sent(a: &[MissionAction]) -> Vec<&MavMessage> {
    a.iter()
        .filter_map(|a| match a {
            MissionAction::Send(m) => Some(&**m),
            _ => None,
        })
        .collect()
}

fn requested(a: &[MissionAction]) -> Vec<u16> {
    sent(a)
        .into_iter()
        .filter_map(|m| match m {
            MavMessage::MISSION_REQUEST_INT(r) => Some(r.seq),
            _ => None,
        })
        .collect()
}

fn acks(a: &[MissionAction]) -> Vec<MavMissionResult> {
    sent(a)
        .into_iter()
        .filter_map(|m| match m {
            MavMessage::MISSION_ACK(r) => Some(r.mavtype),
            _ => None,
        })
        .collect()
}

#[test]
fn upload_with_retries_duplicates_and_download() {
    let mut s = MissionServer::new(None);
    let items = mission2();
    assert_eq!(requested(&s.on_message(&count(4, MISSION), GCS, ms(0))), vec![0]);
    // No answer: re-request after 250 ms, not before.
    assert!(s.on_tick(ms(200)).is_empty());
    assert_eq!(requested(&s.on_tick(ms(250))), vec![0]);
    let a = s.on_message(&MavMessage::MISSION_ITEM_INT(items[0].clone()), GCS, ms(300));
    assert_eq!(requested(&a), vec![1]);
    // A duplicate of item 0 and an out-of-order item 2 are dropped.
    assert!(
        s.on_message(&MavMessage::MISSION_ITEM_INT(items[0].clone()), GCS, ms(310))
            .is_empty()
    );
    assert!(
        s.on_message(&MavMessage::MISSION_ITEM_INT(items[2].clone()), GCS, ms(320))
            .is_empty()
    );
    for (k, it) in items.iter().enumerate().skip(1) {
        let a = s.on_message(&MavMessage::MISSION_ITEM_INT(it.clone()), GCS, ms(400 + k as u64));
        if k < 3 {
            assert_eq!(requested(&a), vec![k as u16 + 1]);
        } else {
            assert_eq!(acks(&a), vec![MavMissionResult::MAV_MISSION_ACCEPTED]);
            assert!(a.contains(&MissionAction::Updated(MISSION)));
        }
    }
    assert_eq!(s.plan(MISSION).items.len(), 4);
    assert_ne!(s.plan(MISSION).opaque_id, 0);
    // The last item again (our ACK was lost): ACK again.
    let a = s.on_message(&MavMessage::MISSION_ITEM_INT(items[3].clone()), GCS, ms(600));
    assert_eq!(acks(&a), vec![MavMissionResult::MAV_MISSION_ACCEPTED]);
    // Download.
    let a = s.on_message(
        &MavMessage::MISSION_REQUEST_LIST(MISSION_REQUEST_LIST_DATA {
            target_system: 1,
            target_component: 1,
            mission_type: MISSION,
        }),
        GCS,
        ms(700),
    );
    assert!(
        matches!(sent(&a)[0], MavMessage::MISSION_COUNT(c) if c.count == 4 && c.opaque_id == s.plan(MISSION).opaque_id)
    );
    let req = |seq| {
        MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
            seq,
            target_system: 1,
            target_component: 1,
            mission_type: MISSION,
        })
    };
    let a = s.on_message(&req(2), GCS, ms(710));
    assert!(matches!(sent(&a)[0], MavMessage::MISSION_ITEM_INT(i) if i.seq == 2 && i.x == items[2].x));
    let a = s.on_message(&req(9), GCS, ms(720));
    assert_eq!(acks(&a), vec![MavMissionResult::MAV_MISSION_INVALID_SEQUENCE]);
}

#[test]
fn transfer_aborts_after_five_seconds_and_keeps_old_plan() {
    let mut s = MissionServer::new(None);
    s.on_message(&count(4, MISSION), GCS, ms(0));
    let mut retries = 0;
    let mut aborted = false;
    for t in (0..6000).step_by(50) {
        for a in s.on_tick(ms(t)) {
            match a {
                MissionAction::Send(_) => retries += 1,
                MissionAction::Text(_, txt) => aborted |= txt == "Operation timeout",
                _ => {}
            }
        }
    }
    assert!(aborted);
    assert!((19..=21).contains(&retries), "retries {retries}");
    assert!(!s.is_receiving());
    assert!(s.plan(MISSION).items.is_empty());
}

#[test]
fn errors_reject_codes_and_clear() {
    let mut s = MissionServer::new(None);
    s.on_message(&count(1, MISSION), GCS, ms(0));
    let mut local = item(0, MavCmd::MAV_CMD_NAV_WAYPOINT, 47.0, 8.0, 10.0);
    local.frame = MavFrame::MAV_FRAME_LOCAL_NED;
    let a = s.on_message(&MavMessage::MISSION_ITEM_INT(local), GCS, ms(1));
    assert_eq!(acks(&a), vec![MavMissionResult::MAV_MISSION_UNSUPPORTED_FRAME]);
    assert!(!s.is_receiving());
    assert_eq!(
        acks(&s.on_message(&count(5000, MISSION), GCS, ms(2))),
        vec![MavMissionResult::MAV_MISSION_NO_SPACE]
    );
    // Wrong mission_type inside a transfer.
    s.on_message(&count(1, MavMissionType::MAV_MISSION_TYPE_FENCE), GCS, ms(3));
    let a = s.on_message(
        &MavMessage::MISSION_ITEM_INT(item(0, MavCmd::MAV_CMD_NAV_WAYPOINT, 47.0, 8.0, 10.0)),
        GCS,
        ms(4),
    );
    assert_eq!(acks(&a), vec![MavMissionResult::MAV_MISSION_ERROR]);
    // Injected rejection.
    let mut r = MissionServer::new(Some(MavMissionResult::MAV_MISSION_DENIED));
    assert_eq!(
        acks(&r.on_message(&count(3, MISSION), GCS, ms(0))),
        vec![MavMissionResult::MAV_MISSION_DENIED]
    );
    // Clear all.
    let a = s.on_message(
        &MavMessage::MISSION_CLEAR_ALL(MISSION_CLEAR_ALL_DATA {
            target_system: 1,
            target_component: 1,
            mission_type: MavMissionType::MAV_MISSION_TYPE_ALL,
        }),
        GCS,
        ms(5),
    );
    assert_eq!(acks(&a), vec![MavMissionResult::MAV_MISSION_ACCEPTED]);
    assert_eq!(a.iter().filter(|a| matches!(a, MissionAction::Updated(_))).count(), 3);
    // count = 0 clears as well.
    assert_eq!(
        acks(&s.on_message(&count(0, MISSION), GCS, ms(6))),
        vec![MavMissionResult::MAV_MISSION_ACCEPTED]
    );
}

#[test]
fn fence_upload_is_stored_separately() {
    let mut s = MissionServer::new(None);
    let fence = MavMissionType::MAV_MISSION_TYPE_FENCE;
    s.on_message(&count(1, fence), GCS, ms(0));
    let mut c = item(0, MavCmd::MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, 47.3977, 8.5456, 0.0);
    c.mission_type = fence;
    c.param1 = 5.0;
    let a = s.on_message(&MavMessage::MISSION_ITEM_INT(c), GCS, ms(1));
    assert_eq!(acks(&a), vec![MavMissionResult::MAV_MISSION_ACCEPTED]);
    assert_eq!(s.plan(fence).items.len(), 1);
    assert!(s.plan(MISSION).items.is_empty());
}
