//! COMMAND_LONG / COMMAND_INT handling with PX4's results; anything unknown is UNSUPPORTED.

use mavlink::dialects::common::{COMMAND_ACK_DATA, MESSAGE_INTERVAL_DATA, MavCmd, MavMessage, MavResult, MavSeverity};

use crate::modes::FlightMode;
use crate::telemetry::{IntervalResult, ids};
use crate::vehicle::Vehicle;

/// PX4's magic param2 that forces arming/disarming.
pub const FORCE_MAGIC: f32 = 21196.0;

#[expect(deprecated, reason = "PX4 still answers MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES")]
impl Vehicle {
    /// Execute a command from `from` and send its COMMAND_ACK.
    pub(crate) fn on_command(&mut self, from: (u8, u8), cmd: MavCmd, p: [f32; 7], is_int: bool) {
        let result = self.execute(cmd, p, is_int);
        self.outbox.push(MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command: cmd,
            result,
            progress: 0,
            result_param2: 0,
            target_system: from.0,
            target_component: from.1,
        }));
        // Requested messages follow their ACK, as in PX4.
        if result == MavResult::MAV_RESULT_ACCEPTED {
            let requested = match cmd {
                MavCmd::MAV_CMD_REQUEST_MESSAGE => Some(p[0] as u32),
                MavCmd::MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES => Some(ids::AUTOPILOT_VERSION),
                MavCmd::MAV_CMD_GET_HOME_POSITION => Some(ids::HOME_POSITION),
                MavCmd::MAV_CMD_GET_MESSAGE_INTERVAL => {
                    let id = p[0] as u32;
                    self.outbox.push(MavMessage::MESSAGE_INTERVAL(MESSAGE_INTERVAL_DATA {
                        interval_us: self.streams.interval_us(id),
                        message_id: id.min(u32::from(u16::MAX)) as u16,
                    }));
                    None
                }
                _ => None,
            };
            if let Some(m) = requested.and_then(|id| self.build_message(id)) {
                self.outbox.push(m);
            }
        }
    }

    fn execute(&mut self, cmd: MavCmd, p: [f32; 7], is_int: bool) -> MavResult {
        use MavResult::*;
        match cmd {
            MavCmd::MAV_CMD_COMPONENT_ARM_DISARM => self.arm_disarm(p[0], p[1]),
            MavCmd::MAV_CMD_DO_SET_MODE => {
                if (p[0] as u32) & 1 == 0 {
                    return MAV_RESULT_DENIED;
                }
                match FlightMode::from_px4(p[1] as u8, p[2] as u8) {
                    Some(mode) => self.try_mode(mode),
                    None => MAV_RESULT_DENIED,
                }
            }
            MavCmd::MAV_CMD_MISSION_START => {
                if self.nav.count() == 0 {
                    self.text(
                        MavSeverity::MAV_SEVERITY_CRITICAL,
                        "Mission start denied! No valid mission",
                    );
                    return MAV_RESULT_DENIED;
                }
                // The current item again is "nothing to do" (PX4 v1.14 mission.cpp set_current_mission_index).
                let first = p[0];
                if first >= 0.0
                    && first.is_finite()
                    && first as usize != self.nav.current()
                    && !self.nav.set_current(first as usize)
                {
                    return MAV_RESULT_DENIED;
                }
                if !self.armed && self.try_arm() != MAV_RESULT_ACCEPTED {
                    return MAV_RESULT_TEMPORARILY_REJECTED;
                }
                // Already flying the mission (armed in AUTO.MISSION): the mode stays, nothing restarts.
                if self.nav.mode() != FlightMode::Mission {
                    self.set_mode(FlightMode::Mission, self.nav_params.takeoff_alt_m);
                }
                MAV_RESULT_ACCEPTED
            }
            MavCmd::MAV_CMD_NAV_TAKEOFF => {
                // param7 is AMSL altitude (NaN: MIS_TAKEOFF_ALT); COMMAND_INT z as well.
                let _ = is_int;
                let rel = if p[6].is_finite() {
                    f64::from(p[6]) - self.origin.alt_m
                } else {
                    f64::NAN
                };
                let alt = if rel.is_finite() && rel > 0.0 {
                    rel
                } else {
                    self.nav_params.takeoff_alt_m
                };
                self.set_mode(FlightMode::Takeoff, alt);
                MAV_RESULT_ACCEPTED
            }
            MavCmd::MAV_CMD_NAV_LAND => {
                self.set_mode(FlightMode::Land, self.nav_params.takeoff_alt_m);
                MAV_RESULT_ACCEPTED
            }
            MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH => {
                self.set_mode(FlightMode::Rtl, self.nav_params.takeoff_alt_m);
                MAV_RESULT_ACCEPTED
            }
            MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL => match self.streams.set_interval(p[0] as u32, p[1], self.now) {
                IntervalResult::Accepted => MAV_RESULT_ACCEPTED,
                IntervalResult::UnknownMessage => MAV_RESULT_DENIED,
                IntervalResult::BadInterval => MAV_RESULT_DENIED,
            },
            MavCmd::MAV_CMD_GET_MESSAGE_INTERVAL => MAV_RESULT_ACCEPTED,
            MavCmd::MAV_CMD_REQUEST_MESSAGE => {
                if p[0].is_finite() && p[0] >= 0.0 && self.build_message(p[0] as u32).is_some() {
                    MAV_RESULT_ACCEPTED
                } else {
                    MAV_RESULT_DENIED
                }
            }
            MavCmd::MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES | MavCmd::MAV_CMD_GET_HOME_POSITION => MAV_RESULT_ACCEPTED,
            _ => MAV_RESULT_UNSUPPORTED,
        }
    }

    fn arm_disarm(&mut self, p1: f32, p2: f32) -> MavResult {
        let force = p2 == FORCE_MAGIC;
        if p1 == 1.0 {
            return self.try_arm();
        }
        if p1 != 0.0 {
            return MavResult::MAV_RESULT_DENIED;
        }
        if !self.landed && !force {
            self.text(MavSeverity::MAV_SEVERITY_CRITICAL, "Disarming denied: not landed");
            return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
        }
        self.disarm("external command");
        MavResult::MAV_RESULT_ACCEPTED
    }

    fn try_arm(&mut self) -> MavResult {
        if self.armed {
            return MavResult::MAV_RESULT_ACCEPTED;
        }
        if self.fail_arm {
            self.text(
                MavSeverity::MAV_SEVERITY_CRITICAL,
                "Arming denied: injected fault (fail-arm)",
            );
            return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
        }
        // Commander answers a refused arming with TEMPORARILY_REJECTED (PX4 v1.14 Commander.cpp, ARM_DISARM).
        if let Err(text) = self.arming_check(self.nav.mode()) {
            if let Some(t) = text {
                self.text(MavSeverity::MAV_SEVERITY_CRITICAL, t);
            }
            return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
        }
        if self.nav.mode() == FlightMode::Offboard && self.offboard.is_none() {
            self.text(
                MavSeverity::MAV_SEVERITY_CRITICAL,
                "Arming denied: no offboard setpoints",
            );
            return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
        }
        self.arm();
        MavResult::MAV_RESULT_ACCEPTED
    }

    fn try_mode(&mut self, mode: FlightMode) -> MavResult {
        match mode {
            // Disarmed, PX4 v1.14 allows every mode change (commander/UserModeIntention.cpp:47).
            FlightMode::Mission if self.nav.count() == 0 && self.armed => {
                self.text(
                    MavSeverity::MAV_SEVERITY_CRITICAL,
                    "Switching to Mission is currently not possible",
                );
                return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
            }
            FlightMode::Posctl if self.armed && self.posctl_refusal().is_some() => {
                let text = self.posctl_refusal().unwrap_or_default();
                self.text(MavSeverity::MAV_SEVERITY_CRITICAL, text);
                return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
            }
            FlightMode::Offboard if self.offboard.is_none() => {
                self.text(
                    MavSeverity::MAV_SEVERITY_CRITICAL,
                    "Switching to Offboard is currently not possible",
                );
                return MavResult::MAV_RESULT_TEMPORARILY_REJECTED;
            }
            _ => {}
        }
        if mode != self.nav.mode() {
            self.set_mode(mode, self.nav_params.takeoff_alt_m);
        }
        MavResult::MAV_RESULT_ACCEPTED
    }
}
