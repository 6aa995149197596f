//! COMMAND_LONG with its COMMAND_ACK as a socket-free state machine: resend on timeout with `confirmation`
//! incremented (MAVLink command protocol), wait longer on MAV_RESULT_IN_PROGRESS, ask again a few times on
//! MAV_RESULT_TEMPORARILY_REJECTED ("try again later", e.g. a pre-arm check not ready yet), any other result
//! is final.

use std::time::Duration;

use mavlink::dialects::common::{COMMAND_LONG_DATA, MavCmd, MavMessage, MavResult};

use super::exchange::{Exchange, ProtocolError, RetryPolicy, Step, Target};

/// How long to keep waiting after an IN_PROGRESS ack before resending (vehicle time).
pub const IN_PROGRESS_WAIT: Duration = Duration::from_secs(5);
/// After MAV_RESULT_TEMPORARILY_REJECTED, ask again after this long (vehicle time)...
pub const TEMPORARY_BACKOFF: Duration = Duration::from_millis(500);
/// ...at most this many times; then the rejection is final.
pub const MAX_TEMPORARY_REJECTIONS: u32 = 3;

/// One command and its acknowledgement.
#[derive(Debug, Clone)]
pub struct AckedCommand {
    target: Target,
    command: MavCmd,
    params: [f32; 7],
    retry: RetryPolicy,
    confirmation: u8,
    in_a_row: u32,
    retries: u32,
    rejections: u32,
    deadline: Duration,
}

impl AckedCommand {
    /// `command` with `params` (param1..param7) to `target`.
    pub fn new(target: Target, command: MavCmd, params: [f32; 7], retry: RetryPolicy) -> Self {
        Self {
            target,
            command,
            params,
            retry,
            confirmation: 0,
            in_a_row: 0,
            retries: 0,
            rejections: 0,
            deadline: Duration::ZERO,
        }
    }

    /// The command id.
    pub fn command(&self) -> MavCmd {
        self.command
    }

    fn msg(&self) -> MavMessage {
        let p = self.params;
        MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
            param1: p[0],
            param2: p[1],
            param3: p[2],
            param4: p[3],
            param5: p[4],
            param6: p[5],
            param7: p[6],
            command: self.command,
            target_system: self.target.system,
            target_component: self.target.component,
            confirmation: self.confirmation,
        })
    }
}

impl Exchange for AckedCommand {
    type Output = ();

    fn start(&mut self, now: Duration) -> Vec<MavMessage> {
        self.deadline = now + self.retry.timeout;
        vec![self.msg()]
    }

    fn on_message(&mut self, msg: &MavMessage, now: Duration) -> Step<()> {
        let MavMessage::COMMAND_ACK(ack) = msg else {
            return Step::wait();
        };
        if ack.command != self.command {
            return Step::wait();
        }
        match ack.result {
            MavResult::MAV_RESULT_ACCEPTED => Step::done(Ok(())),
            MavResult::MAV_RESULT_IN_PROGRESS => {
                self.in_a_row = 0;
                self.deadline = now + IN_PROGRESS_WAIT.max(self.retry.timeout);
                Step::wait()
            }
            MavResult::MAV_RESULT_TEMPORARILY_REJECTED if self.rejections < MAX_TEMPORARY_REJECTIONS => {
                // The resend happens at the deadline, as after a lost answer, without using up those retries.
                self.rejections += 1;
                self.in_a_row = 0;
                self.deadline = now + TEMPORARY_BACKOFF;
                Step::wait()
            }
            result => Step::done(Err(ProtocolError::CommandRefused {
                command: self.command,
                result,
            })),
        }
    }

    fn on_timeout(&mut self, now: Duration) -> Step<()> {
        if self.in_a_row >= self.retry.max_retries {
            return Step::done(Err(ProtocolError::Timeout {
                what: format!("command {:?}", self.command),
                retries: self.in_a_row,
            }));
        }
        self.in_a_row += 1;
        self.retries += 1;
        self.confirmation = self.confirmation.saturating_add(1);
        self.deadline = now + self.retry.timeout;
        Step::send(self.msg())
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
    use mavlink::dialects::common::COMMAND_ACK_DATA;

    const T: Target = Target {
        system: 1,
        component: 1,
    };

    fn ack(command: MavCmd, result: MavResult) -> MavMessage {
        MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command,
            result,
            ..Default::default()
        })
    }

    #[test]
    fn retries_increment_confirmation() {
        let arm = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
        let mut c = AckedCommand::new(T, arm, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], RetryPolicy::COMMAND);
        let mut n = 0;
        let (r, sent) = run_scripted(&mut c, Duration::from_millis(10), |_, _| {
            n += 1;
            if n < 3 {
                vec![]
            } else {
                vec![ack(arm, MavResult::MAV_RESULT_ACCEPTED)]
            }
        });
        assert_eq!(r, Ok(()));
        let conf: Vec<u8> = sent
            .iter()
            .filter_map(|m| match m {
                MavMessage::COMMAND_LONG(c) => Some(c.confirmation),
                _ => None,
            })
            .collect();
        assert_eq!(conf, vec![0, 1, 2]);
        assert_eq!(c.retries(), 2);
    }

    #[test]
    fn in_progress_waits_then_final_result() {
        let cmd = MavCmd::MAV_CMD_MISSION_START;
        let mut c = AckedCommand::new(T, cmd, [0.0; 7], RetryPolicy::COMMAND);
        let (r, sent) = run_scripted(&mut c, Duration::from_millis(10), |_, _| {
            vec![
                ack(MavCmd::MAV_CMD_NAV_LAND, MavResult::MAV_RESULT_DENIED),
                ack(cmd, MavResult::MAV_RESULT_IN_PROGRESS),
                ack(cmd, MavResult::MAV_RESULT_TEMPORARILY_REJECTED),
            ]
        });
        assert_eq!(
            sent.len(),
            1 + MAX_TEMPORARY_REJECTIONS as usize,
            "asked again after each temporary rejection, then gave up"
        );
        let e = r.unwrap_err();
        assert!(
            e.to_string().contains("not possible in the vehicle's current state"),
            "{e}"
        );
    }

    #[test]
    fn a_temporary_rejection_is_asked_again() {
        let cmd = MavCmd::MAV_CMD_COMPONENT_ARM_DISARM;
        let mut c = AckedCommand::new(T, cmd, [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], RetryPolicy::COMMAND);
        let mut asked = 0;
        let (r, sent) = run_scripted(&mut c, Duration::from_millis(10), |_, _| {
            asked += 1;
            let result = if asked < 3 {
                MavResult::MAV_RESULT_TEMPORARILY_REJECTED
            } else {
                MavResult::MAV_RESULT_ACCEPTED
            };
            vec![ack(cmd, result)]
        });
        assert!(r.is_ok(), "{r:?}");
        assert_eq!(sent.len(), 3);
    }

    #[test]
    fn silence_is_bounded() {
        let mut c = AckedCommand::new(T, MavCmd::MAV_CMD_NAV_LAND, [0.0; 7], RetryPolicy::COMMAND);
        let (r, sent) = run_scripted(&mut c, Duration::from_millis(10), |_, _| vec![]);
        let n = RetryPolicy::COMMAND.max_retries;
        assert!(
            matches!(r, Err(ProtocolError::Timeout { retries, .. }) if retries == n),
            "{r:?}"
        );
        assert_eq!(sent.len(), 1 + n as usize);
    }
}
