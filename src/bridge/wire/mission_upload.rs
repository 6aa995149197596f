//! Mission upload (MAVLink mission protocol, GCS side) for any mission type, as a socket-free state machine:
//! MISSION_COUNT, then answer each MISSION_REQUEST(_INT) with its MISSION_ITEM_INT, until MISSION_ACK.

use std::time::Duration;

use mavlink::dialects::common::{
    MISSION_COUNT_DATA, MISSION_ITEM_INT_DATA, MavMessage, MavMissionResult, MavMissionType,
};

use super::exchange::{Exchange, ProtocolError, RetryPolicy, Step, Target};

#[derive(Debug, Clone, Copy, PartialEq)]
enum Sent {
    Count,
    Item(u16),
}

/// Uploads `items` as a plan of one mission type; the output is the vehicle's `opaque_id` (PX4: a CRC32).
#[derive(Debug, Clone)]
pub struct MissionUpload {
    target: Target,
    mission_type: MavMissionType,
    items: Vec<MISSION_ITEM_INT_DATA>,
    retry: RetryPolicy,
    last: Sent,
    /// Highest item sent so far (progress resets the retry budget).
    highest: Option<u16>,
    in_a_row: u32,
    retries: u32,
    deadline: Duration,
}

impl MissionUpload {
    /// An upload of `items` (their `seq`, targets and `mission_type` are set here).
    pub fn new(
        target: Target,
        mission_type: MavMissionType,
        items: Vec<MISSION_ITEM_INT_DATA>,
        retry: RetryPolicy,
    ) -> Self {
        let items = items
            .into_iter()
            .enumerate()
            .map(|(i, mut it)| {
                it.seq = i as u16;
                it.target_system = target.system;
                it.target_component = target.component;
                it.mission_type = mission_type;
                it
            })
            .collect();
        Self {
            target,
            mission_type,
            items,
            retry,
            last: Sent::Count,
            highest: None,
            in_a_row: 0,
            retries: 0,
            deadline: Duration::ZERO,
        }
    }

    fn count_msg(&self) -> MavMessage {
        MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
            count: self.items.len() as u16,
            target_system: self.target.system,
            target_component: self.target.component,
            mission_type: self.mission_type,
            opaque_id: 0,
        })
    }

    fn item_msg(&self, seq: u16) -> Option<MavMessage> {
        self.items
            .get(usize::from(seq))
            .map(|it| MavMessage::MISSION_ITEM_INT(it.clone()))
    }

    fn on_request(&mut self, seq: u16, mission_type: MavMissionType, now: Duration) -> Step<u32> {
        if mission_type != self.mission_type {
            return Step::wait();
        }
        let Some(msg) = self.item_msg(seq) else {
            return Step::wait(); // out of range: a stale request from another transfer
        };
        if self.highest.is_none_or(|h| seq > h) {
            self.highest = Some(seq);
            self.in_a_row = 0;
        }
        self.last = Sent::Item(seq);
        self.deadline = now + self.retry.timeout;
        Step::send(msg)
    }
}

#[expect(deprecated, reason = "PX4 still speaks MISSION_REQUEST and MISSION_ITEM")]
impl Exchange for MissionUpload {
    type Output = u32;

    fn start(&mut self, now: Duration) -> Vec<MavMessage> {
        self.deadline = now + self.retry.timeout;
        vec![self.count_msg()]
    }

    fn on_message(&mut self, msg: &MavMessage, now: Duration) -> Step<u32> {
        match msg {
            MavMessage::MISSION_REQUEST_INT(r) => self.on_request(r.seq, r.mission_type, now),
            MavMessage::MISSION_REQUEST(r) => self.on_request(r.seq, r.mission_type, now),
            MavMessage::MISSION_ACK(a) if a.mission_type == self.mission_type => {
                if a.mavtype != MavMissionResult::MAV_MISSION_ACCEPTED {
                    return Step::done(Err(ProtocolError::MissionRefused {
                        mission_type: self.mission_type,
                        result: a.mavtype,
                    }));
                }
                let complete = match self.items.len() {
                    0 => true,
                    n => self.highest == Some((n - 1) as u16),
                };
                // An ACCEPTED before the last item was requested is left over from an earlier transfer.
                if complete {
                    Step::done(Ok(a.opaque_id))
                } else {
                    Step::wait()
                }
            }
            _ => Step::wait(),
        }
    }

    fn on_timeout(&mut self, now: Duration) -> Step<u32> {
        if self.in_a_row >= self.retry.max_retries {
            return Step::done(Err(ProtocolError::Timeout {
                what: format!("uploading {} {:?} items", self.items.len(), self.mission_type),
                retries: self.in_a_row,
            }));
        }
        self.in_a_row += 1;
        self.retries += 1;
        self.deadline = now + self.retry.timeout;
        // The vehicle re-requests by itself; resending our last message covers a lost count or a lost ACK
        // (PX4 answers a repeated last item with the ACK again).
        let msg = match self.last {
            Sent::Count => Some(self.count_msg()),
            Sent::Item(seq) => self.item_msg(seq),
        };
        match msg {
            Some(m) => Step::send(m),
            None => Step::wait(),
        }
    }

    fn deadline(&self) -> Duration {
        self.deadline
    }

    fn retries(&self) -> u32 {
        self.retries
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::wire::exchange::run_scripted;
    use mavlink::dialects::common::{MISSION_ACK_DATA, MISSION_REQUEST_INT_DATA};

    const T: Target = Target {
        system: 1,
        component: 1,
    };

    fn items(n: usize) -> Vec<MISSION_ITEM_INT_DATA> {
        (0..n)
            .map(|i| MISSION_ITEM_INT_DATA {
                x: i as i32,
                ..Default::default()
            })
            .collect()
    }

    fn req(seq: u16) -> MavMessage {
        MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
            seq,
            ..Default::default()
        })
    }

    fn ack(result: MavMissionResult, id: u32) -> MavMessage {
        MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            mavtype: result,
            opaque_id: id,
            ..Default::default()
        })
    }

    /// A vehicle that requests items in order and ACKs with `result` after the last; `drop` loses messages.
    fn vehicle(
        n: u16,
        result: MavMissionResult,
        mut drop: impl FnMut(usize) -> bool,
    ) -> impl FnMut(&MavMessage, Duration) -> Vec<MavMessage> {
        let mut k = 0;
        move |m, _| {
            k += 1;
            if drop(k) {
                return vec![];
            }
            match m {
                MavMessage::MISSION_COUNT(c) if c.count == 0 => vec![ack(result, 0)],
                MavMessage::MISSION_COUNT(_) => vec![req(0)],
                MavMessage::MISSION_ITEM_INT(it) if it.seq + 1 < n => vec![req(it.seq + 1)],
                MavMessage::MISSION_ITEM_INT(_) => vec![ack(result, 42)],
                _ => vec![],
            }
        }
    }

    #[test]
    fn clean_upload() {
        let mut up = MissionUpload::new(
            T,
            MavMissionType::MAV_MISSION_TYPE_MISSION,
            items(5),
            RetryPolicy::MISSION,
        );
        let ok = MavMissionResult::MAV_MISSION_ACCEPTED;
        let (r, sent) = run_scripted(&mut up, Duration::from_millis(10), vehicle(5, ok, |_| false));
        assert_eq!(r, Ok(42));
        assert_eq!(sent.len(), 6);
        assert_eq!(up.retries(), 0);
        if let MavMessage::MISSION_ITEM_INT(it) = &sent[3] {
            assert_eq!((it.seq, it.target_system, it.x), (2, 1, 2));
        } else {
            panic!("{:?}", sent[3]);
        }
    }

    #[test]
    fn empty_plan_is_a_clear() {
        let mut up = MissionUpload::new(
            T,
            MavMissionType::MAV_MISSION_TYPE_MISSION,
            vec![],
            RetryPolicy::MISSION,
        );
        let ok = MavMissionResult::MAV_MISSION_ACCEPTED;
        let (r, _) = run_scripted(&mut up, Duration::from_millis(10), vehicle(0, ok, |_| false));
        assert_eq!(r, Ok(0));
    }

    #[test]
    fn lost_messages_are_retried() {
        let mut up = MissionUpload::new(
            T,
            MavMissionType::MAV_MISSION_TYPE_MISSION,
            items(4),
            RetryPolicy::MISSION,
        );
        let ok = MavMissionResult::MAV_MISSION_ACCEPTED;
        // Lose the first count, and the answer to item 2 once.
        let (r, _) = run_scripted(&mut up, Duration::from_millis(10), vehicle(4, ok, |k| k == 1 || k == 4));
        assert_eq!(r, Ok(42));
        assert_eq!(up.retries(), 2);
    }

    #[test]
    fn every_refusal_is_an_error_naming_the_code() {
        use MavMissionResult::*;
        for code in [
            MAV_MISSION_ERROR,
            MAV_MISSION_UNSUPPORTED_FRAME,
            MAV_MISSION_UNSUPPORTED,
            MAV_MISSION_NO_SPACE,
            MAV_MISSION_INVALID,
            MAV_MISSION_INVALID_PARAM1,
            MAV_MISSION_INVALID_PARAM7,
            MAV_MISSION_INVALID_SEQUENCE,
            MAV_MISSION_DENIED,
            MAV_MISSION_OPERATION_CANCELLED,
        ] {
            let mut up = MissionUpload::new(
                T,
                MavMissionType::MAV_MISSION_TYPE_MISSION,
                items(3),
                RetryPolicy::MISSION,
            );
            let (r, _) = run_scripted(&mut up, Duration::from_millis(10), vehicle(3, code, |_| false));
            let e = r.unwrap_err();
            assert!(matches!(e, ProtocolError::MissionRefused { result, .. } if result == code));
            let text = e.to_string();
            assert!(
                text.contains("refused the mission upload") && text.contains(&(code as u32).to_string()),
                "{text}"
            );
        }
    }

    #[test]
    fn silence_times_out_after_bounded_retries() {
        let mut up = MissionUpload::new(
            T,
            MavMissionType::MAV_MISSION_TYPE_MISSION,
            items(3),
            RetryPolicy::MISSION,
        );
        let (r, sent) = run_scripted(&mut up, Duration::from_millis(10), |_, _| vec![]);
        let n = RetryPolicy::MISSION.max_retries;
        assert!(
            matches!(r, Err(ProtocolError::Timeout { retries, .. }) if retries == n),
            "{r:?}"
        );
        assert_eq!(sent.len(), 1 + n as usize, "count + retries");
    }

    #[test]
    fn other_types_and_stale_acks_are_ignored() {
        let mut up = MissionUpload::new(
            T,
            MavMissionType::MAV_MISSION_TYPE_MISSION,
            items(2),
            RetryPolicy::MISSION,
        );
        up.start(Duration::ZERO);
        let accepted = ack(MavMissionResult::MAV_MISSION_ACCEPTED, 1);
        assert!(
            up.on_message(&accepted, Duration::ZERO).done.is_none(),
            "ACK before the items"
        );
        let fence_req = MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
            seq: 0,
            mission_type: MavMissionType::MAV_MISSION_TYPE_FENCE,
            ..Default::default()
        });
        assert!(up.on_message(&fence_req, Duration::ZERO).send.is_empty());
        assert!(up.on_message(&req(7), Duration::ZERO).send.is_empty(), "out of range");
    }
}
