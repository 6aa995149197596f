//! PX4's mission transfer protocol (upload, download, clear) as a pure state machine.
//!
//! No sockets and no clock: `on_message(msg, from, now)` and `on_tick(now)` return the actions
//! to take, so tests script messages with a fake time.

use std::time::Duration;

#[expect(deprecated, reason = "PX4 still speaks MISSION_REQUEST and MISSION_ITEM")]
use mavlink::dialects::common::{
    MISSION_ACK_DATA, MISSION_COUNT_DATA, MISSION_ITEM_INT_DATA, MISSION_REQUEST_DATA, MISSION_REQUEST_INT_DATA,
    MavMessage, MavMissionResult, MavMissionType, MavSeverity,
};

use crate::mission_items::{from_float_item, plan_checksum, to_float_item, validate_item};

/// PX4 re-sends its item request after this long without an answer.
pub const RETRY_TIMEOUT: Duration = Duration::from_millis(250);
/// PX4 aborts a transfer after this long without progress.
pub const PROTOCOL_TIMEOUT: Duration = Duration::from_secs(5);

/// What the vehicle must do after a mission-protocol message.
#[derive(Debug, Clone, PartialEq)]
pub enum MissionAction {
    /// Send this message.
    Send(Box<MavMessage>),
    /// Send a STATUSTEXT.
    Text(MavSeverity, String),
    /// The stored plan of this type changed (upload finished or cleared).
    Updated(MavMissionType),
}

/// A stored plan: items and the checksum reported as `opaque_id`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Plan {
    /// Items in sequence order (`seq` = index).
    pub items: Vec<MISSION_ITEM_INT_DATA>,
    /// CRC-32 of the items.
    pub opaque_id: u32,
}

#[derive(Debug, Clone)]
enum Transfer {
    Idle,
    Receiving {
        ty: MavMissionType,
        count: u16,
        items: Vec<MISSION_ITEM_INT_DATA>,
        int_mode: bool,
        partner: (u8, u8),
        last_activity: Duration,
        last_request: Duration,
    },
    Sending {
        last_activity: Duration,
    },
}

/// Mission, fence and rally storage plus the one transfer in progress.
#[derive(Debug, Clone)]
pub struct MissionServer {
    plans: [Plan; 3],
    transfer: Transfer,
    reject: Option<MavMissionResult>,
    last_upload: Option<(MavMissionType, u16)>,
}

fn slot(ty: MavMissionType) -> Option<usize> {
    match ty {
        MavMissionType::MAV_MISSION_TYPE_MISSION => Some(0),
        MavMissionType::MAV_MISSION_TYPE_FENCE => Some(1),
        MavMissionType::MAV_MISSION_TYPE_RALLY => Some(2),
        _ => None,
    }
}

fn capacity(ty: MavMissionType) -> u16 {
    match ty {
        MavMissionType::MAV_MISSION_TYPE_MISSION => 2000,
        MavMissionType::MAV_MISSION_TYPE_FENCE => 256,
        _ => 64,
    }
}

fn ack(partner: (u8, u8), ty: MavMissionType, result: MavMissionResult, opaque_id: u32) -> MissionAction {
    MissionAction::Send(Box::new(MavMessage::MISSION_ACK(MISSION_ACK_DATA {
        target_system: partner.0,
        target_component: partner.1,
        mavtype: result,
        mission_type: ty,
        opaque_id,
    })))
}

#[expect(deprecated, reason = "PX4 still speaks MISSION_REQUEST and MISSION_ITEM")]
impl MissionServer {
    /// Empty storage; `reject` makes every upload fail with that code (fault injection).
    pub fn new(reject: Option<MavMissionResult>) -> Self {
        Self {
            plans: Default::default(),
            transfer: Transfer::Idle,
            reject,
            last_upload: None,
        }
    }

    /// The stored plan of `ty` (MISSION, FENCE or RALLY).
    pub fn plan(&self, ty: MavMissionType) -> &Plan {
        &self.plans[slot(ty).unwrap_or(0)]
    }

    /// True while an upload is in progress.
    pub fn is_receiving(&self) -> bool {
        matches!(self.transfer, Transfer::Receiving { .. })
    }

    /// Handle a message from `from` = (sysid, compid); non-mission messages return nothing.
    pub fn on_message(&mut self, msg: &MavMessage, from: (u8, u8), now: Duration) -> Vec<MissionAction> {
        match msg {
            MavMessage::MISSION_COUNT(c) => self.on_count(c, from, now),
            MavMessage::MISSION_ITEM_INT(it) => self.on_item(it.clone(), true, from, now),
            MavMessage::MISSION_ITEM(it) => self.on_item(from_float_item(it), false, from, now),
            MavMessage::MISSION_REQUEST_LIST(r) => self.on_request_list(r.mission_type, from, now),
            MavMessage::MISSION_REQUEST_INT(r) => self.on_request(r.seq, r.mission_type, true, from, now),
            MavMessage::MISSION_REQUEST(r) => self.on_request(r.seq, r.mission_type, false, from, now),
            MavMessage::MISSION_ACK(_) => {
                if matches!(self.transfer, Transfer::Sending { .. }) {
                    self.transfer = Transfer::Idle;
                }
                vec![]
            }
            MavMessage::MISSION_CLEAR_ALL(c) => self.on_clear(c.mission_type, from),
            _ => vec![],
        }
    }

    /// Timers: re-request the awaited item, abort stale transfers.
    pub fn on_tick(&mut self, now: Duration) -> Vec<MissionAction> {
        match &mut self.transfer {
            Transfer::Receiving {
                last_activity,
                last_request,
                ..
            } => {
                if now.saturating_sub(*last_activity) > PROTOCOL_TIMEOUT {
                    self.transfer = Transfer::Idle;
                    return vec![MissionAction::Text(
                        MavSeverity::MAV_SEVERITY_CRITICAL,
                        "Operation timeout".into(),
                    )];
                }
                if now.saturating_sub(*last_request) >= RETRY_TIMEOUT {
                    *last_request = now;
                    return self.request_next().into_iter().collect();
                }
                vec![]
            }
            Transfer::Sending { last_activity } => {
                if now.saturating_sub(*last_activity) > PROTOCOL_TIMEOUT {
                    self.transfer = Transfer::Idle;
                }
                vec![]
            }
            Transfer::Idle => vec![],
        }
    }

    fn request_next(&self) -> Option<MissionAction> {
        let Transfer::Receiving {
            ty,
            items,
            int_mode,
            partner,
            ..
        } = &self.transfer
        else {
            return None;
        };
        let seq = items.len() as u16;
        let (target_system, target_component) = *partner;
        Some(MissionAction::Send(Box::new(if *int_mode {
            MavMessage::MISSION_REQUEST_INT(MISSION_REQUEST_INT_DATA {
                seq,
                target_system,
                target_component,
                mission_type: *ty,
            })
        } else {
            MavMessage::MISSION_REQUEST(MISSION_REQUEST_DATA {
                seq,
                target_system,
                target_component,
                mission_type: *ty,
            })
        })))
    }

    fn on_count(&mut self, c: &MISSION_COUNT_DATA, from: (u8, u8), now: Duration) -> Vec<MissionAction> {
        let ty = c.mission_type;
        let Some(i) = slot(ty) else {
            return vec![ack(from, ty, MavMissionResult::MAV_MISSION_ERROR, 0)];
        };
        if let Some(code) = self.reject {
            return vec![
                MissionAction::Text(
                    MavSeverity::MAV_SEVERITY_WARNING,
                    format!("Mission upload rejected (injected fault {})", code as u32),
                ),
                ack(from, ty, code, 0),
            ];
        }
        if c.count > capacity(ty) {
            return vec![ack(from, ty, MavMissionResult::MAV_MISSION_NO_SPACE, 0)];
        }
        if c.count == 0 {
            self.transfer = Transfer::Idle;
            self.plans[i] = Plan::default();
            return vec![
                ack(from, ty, MavMissionResult::MAV_MISSION_ACCEPTED, 0),
                MissionAction::Updated(ty),
            ];
        }
        // A repeated or new count restarts the upload: the client gave up on the old one.
        self.transfer = Transfer::Receiving {
            ty,
            count: c.count,
            items: Vec::with_capacity(c.count as usize),
            int_mode: true,
            partner: from,
            last_activity: now,
            last_request: now,
        };
        self.request_next().into_iter().collect()
    }

    fn on_item(&mut self, item: MISSION_ITEM_INT_DATA, int: bool, from: (u8, u8), now: Duration) -> Vec<MissionAction> {
        let Transfer::Receiving {
            ty,
            count,
            items,
            int_mode,
            last_activity,
            last_request,
            ..
        } = &mut self.transfer
        else {
            // The ACK for the last item may have been lost: PX4 answers the repeat with the ACK.
            return match self.last_upload {
                Some((ty, last)) if ty == item.mission_type && last == item.seq => {
                    let id = self.plan(ty).opaque_id;
                    vec![ack(from, ty, MavMissionResult::MAV_MISSION_ACCEPTED, id)]
                }
                _ => vec![],
            };
        };
        if item.mission_type != *ty {
            let ty = *ty;
            self.transfer = Transfer::Idle;
            return vec![ack(from, ty, MavMissionResult::MAV_MISSION_ERROR, 0)];
        }
        *int_mode = int;
        if usize::from(item.seq) != items.len() {
            // Duplicate or out of order: drop it; the retry timer asks again for the right one.
            return vec![];
        }
        if let Err(code) = validate_item(*ty, &item) {
            let ty = *ty;
            self.transfer = Transfer::Idle;
            return vec![
                MissionAction::Text(
                    MavSeverity::MAV_SEVERITY_CRITICAL,
                    format!("Mission item {} rejected (result {})", item.seq, code as u32),
                ),
                ack(from, ty, code, 0),
            ];
        }
        items.push(item);
        *last_activity = now;
        *last_request = now;
        if items.len() < usize::from(*count) {
            return self.request_next().into_iter().collect();
        }
        let (ty, items) = (*ty, std::mem::take(items));
        self.transfer = Transfer::Idle;
        if ty == MavMissionType::MAV_MISSION_TYPE_FENCE
            && let Err(e) = crate::fence::Fence::validate(&items)
        {
            return vec![
                MissionAction::Text(MavSeverity::MAV_SEVERITY_CRITICAL, e),
                ack(from, ty, MavMissionResult::MAV_MISSION_INVALID, 0),
            ];
        }
        let opaque_id = plan_checksum(&items);
        self.last_upload = Some((ty, (items.len() - 1) as u16));
        if let Some(i) = slot(ty) {
            self.plans[i] = Plan { items, opaque_id };
        }
        vec![
            ack(from, ty, MavMissionResult::MAV_MISSION_ACCEPTED, opaque_id),
            MissionAction::Updated(ty),
        ]
    }

    fn on_request_list(&mut self, ty: MavMissionType, from: (u8, u8), now: Duration) -> Vec<MissionAction> {
        let Some(i) = slot(ty) else {
            return vec![ack(from, ty, MavMissionResult::MAV_MISSION_ERROR, 0)];
        };
        if self.is_receiving() {
            return vec![MissionAction::Text(
                MavSeverity::MAV_SEVERITY_WARNING,
                "WPM: IGN REQUEST LIST: Busy".into(),
            )];
        }
        let plan = &self.plans[i];
        if !plan.items.is_empty() {
            self.transfer = Transfer::Sending { last_activity: now };
        }
        vec![MissionAction::Send(Box::new(MavMessage::MISSION_COUNT(
            MISSION_COUNT_DATA {
                count: plan.items.len() as u16,
                target_system: from.0,
                target_component: from.1,
                mission_type: ty,
                opaque_id: plan.opaque_id,
            },
        )))]
    }

    fn on_request(
        &mut self,
        seq: u16,
        ty: MavMissionType,
        int: bool,
        from: (u8, u8),
        now: Duration,
    ) -> Vec<MissionAction> {
        if self.is_receiving() {
            return vec![];
        }
        let Some(item) = slot(ty).and_then(|i| self.plans[i].items.get(usize::from(seq))) else {
            return vec![ack(from, ty, MavMissionResult::MAV_MISSION_INVALID_SEQUENCE, 0)];
        };
        let mut item = item.clone();
        item.target_system = from.0;
        item.target_component = from.1;
        self.transfer = Transfer::Sending { last_activity: now };
        let msg = if int {
            MavMessage::MISSION_ITEM_INT(item)
        } else {
            MavMessage::MISSION_ITEM(to_float_item(&item))
        };
        vec![MissionAction::Send(Box::new(msg))]
    }

    fn on_clear(&mut self, ty: MavMissionType, from: (u8, u8)) -> Vec<MissionAction> {
        let cleared: Vec<MavMissionType> = match ty {
            MavMissionType::MAV_MISSION_TYPE_ALL => vec![
                MavMissionType::MAV_MISSION_TYPE_MISSION,
                MavMissionType::MAV_MISSION_TYPE_FENCE,
                MavMissionType::MAV_MISSION_TYPE_RALLY,
            ],
            t if slot(t).is_some() => vec![t],
            _ => return vec![ack(from, ty, MavMissionResult::MAV_MISSION_ERROR, 0)],
        };
        self.transfer = Transfer::Idle;
        let mut out = vec![ack(from, ty, MavMissionResult::MAV_MISSION_ACCEPTED, 0)];
        for t in cleared {
            if let Some(i) = slot(t) {
                self.plans[i] = Plan::default();
            }
            out.push(MissionAction::Updated(t));
        }
        out
    }
}

#[cfg(test)]
#[path = "mission_server_tests.rs"]
mod tests;
