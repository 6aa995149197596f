//! What the bridge knows about the vehicle, folded from its messages: armed, mode, landed state, home,
//! pose, mission progress, and whether it rebooted. Pure; every task keeps its own copy.

use std::time::Duration;

use mavlink::dialects::common::{MavAutopilot, MavLandedState, MavMessage, MavModeFlag, MavSeverity};

use super::geo_view::GeoView;
use super::pose::PoseNed;
use super::text_chunks::{Chunk, Joiner};

/// PX4 main mode AUTO.
pub const PX4_MAIN_AUTO: u8 = 4;
/// PX4 main mode OFFBOARD.
pub const PX4_MAIN_OFFBOARD: u8 = 6;
/// PX4 AUTO sub-mode MISSION.
pub const PX4_SUB_MISSION: u8 = 4;

/// The vehicle as last heard.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VehicleView {
    /// Vehicle-clock time of the last message.
    pub last_heard: Option<Duration>,
    /// From HEARTBEAT base_mode.
    pub armed: bool,
    /// PX4 (main, sub) mode from HEARTBEAT custom_mode.
    pub px4_mode: (u8, u8),
    /// From EXTENDED_SYS_STATE.
    pub landed_state: Option<MavLandedState>,
    /// Home received (HOME_POSITION).
    pub home_known: bool,
    /// Latest pose.
    pub pose: Option<PoseNed>,
    /// Ever seen airborne while armed (takeoff happened).
    pub took_off: bool,
    /// Highest MISSION_ITEM_REACHED seq.
    pub reached: Option<u16>,
    /// The vehicle's boot clock went backwards: it rebooted.
    pub rebooted: bool,
    /// STATUSTEXTs of severity warning or worse, in order (a chunked one once whole).
    pub warnings: Vec<String>,
    /// Where the vehicle is placed on Earth (home, EKF origin, global position).
    pub geo: GeoView,
    max_boot_ms: u32,
    texts: Joiner,
}

impl VehicleView {
    /// Takes in what arrives on `rx` until `wake` (wall time) has passed or one message came; a closed
    /// link just waits, so a companion loop keeps its own schedule.
    pub async fn update_within(
        &mut self,
        rx: &mut tokio::sync::broadcast::Receiver<std::sync::Arc<super::link::Inbound>>,
        clock: &super::clock::VehicleClock,
        wake: Duration,
    ) {
        use tokio::sync::broadcast::error::RecvError;
        tokio::select! {
            r = rx.recv() => match r {
                Ok(inb) => self.update(&inb.msg, clock.now()),
                Err(RecvError::Lagged(_)) => {}
                Err(RecvError::Closed) => tokio::time::sleep(wake).await,
            },
            _ = tokio::time::sleep(wake) => {}
        }
    }

    /// Folds one message in, at vehicle-clock time `now`.
    pub fn update(&mut self, msg: &MavMessage, now: Duration) {
        self.last_heard = Some(now);
        self.geo.update(msg, self.pose.as_ref());
        match msg {
            MavMessage::HEARTBEAT(h) if h.autopilot != MavAutopilot::MAV_AUTOPILOT_INVALID => {
                self.armed = h.base_mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                self.px4_mode = (((h.custom_mode >> 16) & 0xFF) as u8, (h.custom_mode >> 24) as u8);
            }
            MavMessage::EXTENDED_SYS_STATE(s) => {
                self.landed_state = Some(s.landed_state);
                if self.armed
                    && matches!(
                        s.landed_state,
                        MavLandedState::MAV_LANDED_STATE_IN_AIR | MavLandedState::MAV_LANDED_STATE_TAKEOFF
                    )
                {
                    self.took_off = true;
                }
            }
            MavMessage::HOME_POSITION(_) => self.home_known = true,
            MavMessage::LOCAL_POSITION_NED(p) => {
                self.boot_time(p.time_boot_ms);
                let pose = self.pose.get_or_insert_with(PoseNed::default);
                pose.time_boot_ms = p.time_boot_ms;
                pose.pos_ned = [p.x.into(), p.y.into(), p.z.into()];
                pose.vel_ned = [p.vx.into(), p.vy.into(), p.vz.into()];
                if self.armed && p.z < -0.5 {
                    self.took_off = true;
                }
            }
            MavMessage::ATTITUDE(a) => {
                self.boot_time(a.time_boot_ms);
                if let Some(pose) = self.pose.as_mut() {
                    pose.yaw_rad = Some(a.yaw.into());
                }
            }
            MavMessage::MISSION_ITEM_REACHED(r) => {
                self.reached = Some(self.reached.map_or(r.seq, |s| s.max(r.seq)));
            }
            MavMessage::STATUSTEXT(t) => {
                if let Some(chunk) = Chunk::of(t) {
                    let whole = self.texts.feed(chunk);
                    whole.into_iter().for_each(|w| self.keep_text(w));
                }
            }
            _ => {}
        }
    }

    /// A STATUSTEXT chunk still waiting for the rest of its text goes to the warnings as it is.
    pub fn flush_texts(&mut self) {
        if let Some(w) = self.texts.flush() {
            self.keep_text(w);
        }
    }

    fn keep_text(&mut self, (severity, text): (MavSeverity, String)) {
        if severity as u8 <= MavSeverity::MAV_SEVERITY_WARNING as u8 {
            // PX4 ends a text it also sends as an event with a tab (QGC's marker), e.g. "Failsafe activated\t".
            self.warnings.push(text.trim_end().to_string());
        }
    }

    /// A boot clock more than 1 s behind the highest seen means a reboot (datagrams may be reordered slightly).
    fn boot_time(&mut self, ms: u32) {
        if ms.saturating_add(1000) < self.max_boot_ms {
            self.rebooted = true;
        }
        self.max_boot_ms = self.max_boot_ms.max(ms);
    }

    /// Landed and disarmed after a takeoff: the flight is over.
    pub fn landed_after_flight(&self) -> bool {
        self.took_off
            && !self.armed
            && self
                .landed_state
                .is_none_or(|s| s == MavLandedState::MAV_LANDED_STATE_ON_GROUND)
    }

    /// Vehicle time since the last message (None if never heard).
    pub fn silent_for(&self, now: Duration) -> Option<Duration> {
        self.last_heard.map(|t| now.saturating_sub(t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::wire::text_chunks::FIELD_CHARS;
    use mavlink::dialects::common::{
        EXTENDED_SYS_STATE_DATA, HEARTBEAT_DATA, LOCAL_POSITION_NED_DATA, MavState, MavType, MavVtolState,
        STATUSTEXT_DATA,
    };

    fn hb(armed: bool) -> MavMessage {
        let mut base = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
        if armed {
            base |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: (4 << 24) | (4 << 16),
            mavtype: MavType::MAV_TYPE_QUADROTOR,
            autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
            base_mode: base,
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        })
    }

    fn landed(s: MavLandedState) -> MavMessage {
        MavMessage::EXTENDED_SYS_STATE(EXTENDED_SYS_STATE_DATA {
            vtol_state: MavVtolState::MAV_VTOL_STATE_UNDEFINED,
            landed_state: s,
        })
    }

    fn pos(ms: u32, z: f32) -> MavMessage {
        MavMessage::LOCAL_POSITION_NED(LOCAL_POSITION_NED_DATA {
            time_boot_ms: ms,
            z,
            ..Default::default()
        })
    }

    #[test]
    fn flight_life_cycle() {
        let mut v = VehicleView::default();
        let t = Duration::ZERO;
        v.update(&landed(MavLandedState::MAV_LANDED_STATE_ON_GROUND), t);
        v.update(&hb(false), t);
        assert!(!v.landed_after_flight(), "never flew");
        v.update(&hb(true), t);
        assert_eq!(v.px4_mode, (4, 4));
        v.update(&pos(100, -3.0), t);
        assert!(v.took_off);
        v.update(&landed(MavLandedState::MAV_LANDED_STATE_ON_GROUND), t);
        assert!(!v.landed_after_flight(), "still armed");
        v.update(&hb(false), Duration::from_secs(3));
        assert!(v.landed_after_flight());
        assert_eq!(v.silent_for(Duration::from_secs(5)), Some(Duration::from_secs(2)));
    }

    #[test]
    fn warnings_lose_px4s_trailing_tab_and_infos_are_not_warnings() {
        let mut v = VehicleView::default();
        for (severity, text) in [
            (MavSeverity::MAV_SEVERITY_CRITICAL, "Failsafe activated\t"),
            (MavSeverity::MAV_SEVERITY_INFO, "Takeoff detected"),
            (MavSeverity::MAV_SEVERITY_WARNING, "Preflight Fail: Geofence violation"),
        ] {
            let msg = MavMessage::STATUSTEXT(STATUSTEXT_DATA {
                severity,
                text: text.into(),
                id: 0,
                chunk_seq: 0,
            });
            v.update(&msg, Duration::ZERO);
        }
        assert_eq!(v.warnings, ["Failsafe activated", "Preflight Fail: Geofence violation"]);
    }

    #[test]
    fn a_warning_sent_in_chunks_is_one_warning() {
        let mut v = VehicleView::default();
        let long = "Arming denied: Resolve system health failures first";
        let chunks = mock_autopilot::status_text::chunks(MavSeverity::MAV_SEVERITY_WARNING, long, 12);
        assert_eq!(chunks.len(), 2, "sent as PX4 sends it");
        for c in chunks {
            v.update(&MavMessage::STATUSTEXT(c), Duration::ZERO);
        }
        assert_eq!(v.warnings, [long]);
        // A text whose last chunk never came is kept as far as it came.
        let cut = &mock_autopilot::status_text::chunks(MavSeverity::MAV_SEVERITY_WARNING, long, 13)[0];
        v.update(&MavMessage::STATUSTEXT(cut.clone()), Duration::ZERO);
        assert_eq!(v.warnings.len(), 1, "still waiting for its end");
        v.flush_texts();
        assert_eq!(v.warnings[1], &long[..FIELD_CHARS]);
    }

    #[test]
    fn reboot_is_a_boot_clock_going_back() {
        let mut v = VehicleView::default();
        v.update(&pos(50_000, 0.0), Duration::ZERO);
        v.update(&pos(49_500, 0.0), Duration::ZERO);
        assert!(!v.rebooted, "small reordering");
        v.update(&pos(200, 0.0), Duration::ZERO);
        assert!(v.rebooted);
    }
}
