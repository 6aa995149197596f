//! Mission download (GCS side) as a socket-free state machine: MISSION_REQUEST_LIST, MISSION_COUNT, then
//! MISSION_REQUEST_INT for each item, and our MISSION_ACK at the end. Used to check an upload.

use std::time::Duration;

use mavlink::dialects::common::{
    MISSION_ACK_DATA, MISSION_ITEM_INT_DATA, MISSION_REQUEST_INT_DATA, MISSION_REQUEST_LIST_DATA, MavMessage,
    MavMissionResult, MavMissionType,
};

use super::exchange::{Exchange, ProtocolError, RetryPolicy, Step, Target};

/// Downloads the plan of one mission type.
#[derive(Debug, Clone)]
pub struct MissionDownload {
    target: Target,
    mission_type: MavMissionType,
    retry: RetryPolicy,
    count: Option<u16>,
    items: Vec<MISSION_ITEM_INT_DATA>,
    in_a_row: u32,
    retries: u32,
    deadline: Duration,
}

impl MissionDownload {
    /// A download of `mission_type` from `target`.
    pub fn new(target: Target, mission_type: MavMissionType, retry: RetryPolicy) -> Self {
        Self {
            target,
            mission_type,
            retry,
            count: None,
            items: Vec::new(),
            in_a_row: 0,
            retries: 0,
            deadline: Duration::ZERO,
        }
    }

    fn list_msg(&self) -> MavMessage {
        MavMessage::MISSION_REQUEST_LIST(MISSION_REQUEST_LIST_DATA {
            target_system: self.target.system,
            target_component: self.target.component,
            mission_type: self.mission_type,
        })
    }

    fn request_msg(&self) -> MavMessage {
        MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
            seq: self.items.len() as u16,
            target_system: self.target.system,
            target_component: self.target.component,
            mission_type: self.mission_type,
        })
    }

    fn ack_msg(&self) -> MavMessage {
        MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            target_system: self.target.system,
            target_component: self.target.component,
            mavtype: MavMissionResult::MAV_MISSION_ACCEPTED,
            mission_type: self.mission_type,
            opaque_id: 0,
        })
    }

    fn progress(&mut self, now: Duration) {
        self.in_a_row = 0;
        self.deadline = now + self.retry.timeout;
    }

    fn next(&mut self, now: Duration) -> Step<Vec<MISSION_ITEM_INT_DATA>> {
        self.progress(now);
        if self.count.is_some_and(|c| self.items.len() >= usize::from(c)) {
            let items = std::mem::take(&mut self.items);
            return Step::send_then(self.ack_msg(), Ok(items));
        }
        Step::send(self.request_msg())
    }
}

impl Exchange for MissionDownload {
    type Output = Vec<MISSION_ITEM_INT_DATA>;

    fn start(&mut self, now: Duration) -> Vec<MavMessage> {
        self.deadline = now + self.retry.timeout;
        vec![self.list_msg()]
    }

    fn on_message(&mut self, msg: &MavMessage, now: Duration) -> Step<Self::Output> {
        match msg {
            MavMessage::MISSION_COUNT(c) if c.mission_type == self.mission_type && self.count.is_none() => {
                self.count = Some(c.count);
                self.next(now)
            }
            MavMessage::MISSION_ITEM_INT(it)
                if it.mission_type == self.mission_type
                    && self.count.is_some()
                    && usize::from(it.seq) == self.items.len() =>
            {
                self.items.push(it.clone());
                self.next(now)
            }
            MavMessage::MISSION_ACK(a)
                if a.mission_type == self.mission_type && a.mavtype != MavMissionResult::MAV_MISSION_ACCEPTED =>
            {
                Step::done(Err(ProtocolError::MissionRefused {
                    mission_type: self.mission_type,
                    result: a.mavtype,
                }))
            }
            _ => Step::wait(),
        }
    }

    fn on_timeout(&mut self, now: Duration) -> Step<Self::Output> {
        if self.in_a_row >= self.retry.max_retries {
            return Step::done(Err(ProtocolError::Timeout {
                what: format!("downloading the {:?} plan", self.mission_type),
                retries: self.in_a_row,
            }));
        }
        self.in_a_row += 1;
        self.retries += 1;
        self.deadline = now + self.retry.timeout;
        Step::send(match self.count {
            None => self.list_msg(),
            Some(_) => self.request_msg(),
        })
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
    use mavlink::dialects::common::MISSION_COUNT_DATA;

    const T: Target = Target {
        system: 1,
        component: 1,
    };

    fn vehicle(n: u16, mut drop: impl FnMut(usize) -> bool) -> impl FnMut(&MavMessage, Duration) -> Vec<MavMessage> {
        let mut k = 0;
        move |m, _| {
            k += 1;
            if drop(k) {
                return vec![];
            }
            match m {
                MavMessage::MISSION_REQUEST_LIST(_) => vec![MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
                    count: n,
                    ..Default::default()
                })],
                MavMessage::MISSION_REQUEST_INT(r) => vec![MavMessage::MISSION_ITEM_INT(MISSION_ITEM_INT_DATA {
                    seq: r.seq,
                    x: i32::from(r.seq) * 10,
                    ..Default::default()
                })],
                _ => vec![],
            }
        }
    }

    #[test]
    fn downloads_in_order_and_acks() {
        let mut d = MissionDownload::new(T, MavMissionType::MAV_MISSION_TYPE_MISSION, RetryPolicy::MISSION);
        let (r, sent) = run_scripted(&mut d, Duration::from_millis(10), vehicle(3, |_| false));
        let items = r.unwrap();
        assert_eq!(items.iter().map(|i| i.x).collect::<Vec<_>>(), vec![0, 10, 20]);
        assert!(
            matches!(sent.last(), Some(MavMessage::MISSION_ACK(a)) if a.mavtype == MavMissionResult::MAV_MISSION_ACCEPTED)
        );
    }

    #[test]
    fn empty_and_lossy() {
        let mut d = MissionDownload::new(T, MavMissionType::MAV_MISSION_TYPE_MISSION, RetryPolicy::MISSION);
        let (r, _) = run_scripted(&mut d, Duration::from_millis(10), vehicle(0, |_| false));
        assert_eq!(r.unwrap().len(), 0);
        let mut d = MissionDownload::new(T, MavMissionType::MAV_MISSION_TYPE_MISSION, RetryPolicy::MISSION);
        let (r, _) = run_scripted(&mut d, Duration::from_millis(10), vehicle(4, |k| k % 3 == 1));
        assert_eq!(r.unwrap().len(), 4);
        assert!(d.retries() >= 2);
    }

    #[test]
    fn silence_and_refusal() {
        let mut d = MissionDownload::new(T, MavMissionType::MAV_MISSION_TYPE_MISSION, RetryPolicy::MISSION);
        let (r, _) = run_scripted(&mut d, Duration::from_millis(10), |_, _| vec![]);
        assert!(matches!(r, Err(ProtocolError::Timeout { .. })));
        let mut d = MissionDownload::new(T, MavMissionType::MAV_MISSION_TYPE_MISSION, RetryPolicy::MISSION);
        let (r, _) = run_scripted(&mut d, Duration::from_millis(10), |_, _| {
            vec![MavMessage::MISSION_ACK(MISSION_ACK_DATA {
                mavtype: MavMissionResult::MAV_MISSION_INVALID_SEQUENCE,
                ..Default::default()
            })]
        });
        assert!(r.unwrap_err().to_string().contains("out of sequence"));
    }
}
