//! Several COMMAND_LONGs sent back to back, each acknowledged on its own ([`AckedCommand`]): the exchange is
//! done when every command is accepted and fails with the first that fails. Sent while PX4's clock stands
//! still, a batch reaches PX4 as one: ARM and MISSION_START taken at the same simulated instant.

use std::time::Duration;

use mavlink::dialects::common::MavMessage;

use super::command::AckedCommand;
use super::exchange::{Exchange, ProtocolError, Step};

/// Commands in flight together.
#[derive(Debug, Clone)]
pub struct AckedBatch {
    commands: Vec<(AckedCommand, bool)>,
}

impl AckedBatch {
    /// The batch of `commands`, sent in this order.
    pub fn new(commands: Vec<AckedCommand>) -> Self {
        Self {
            commands: commands.into_iter().map(|c| (c, false)).collect(),
        }
    }

    /// Feeds `f` to every command not yet accepted, collecting what they send; the batch's step.
    fn each(&mut self, mut f: impl FnMut(&mut AckedCommand) -> Option<Step<()>>) -> Step<()> {
        let mut send = Vec::new();
        for (c, accepted) in self.commands.iter_mut().filter(|(_, a)| !*a) {
            let Some(step) = f(c) else { continue };
            send.extend(step.send);
            match step.done {
                Some(Ok(())) => *accepted = true,
                Some(Err(e)) => {
                    return Step {
                        send,
                        done: Some(Err(e)),
                    };
                }
                None => {}
            }
        }
        let done = self
            .commands
            .iter()
            .all(|(_, a)| *a)
            .then_some(Ok::<(), ProtocolError>(()));
        Step { send, done }
    }
}

impl Exchange for AckedBatch {
    type Output = ();

    fn start(&mut self, now: Duration) -> Vec<MavMessage> {
        self.commands.iter_mut().flat_map(|(c, _)| c.start(now)).collect()
    }

    fn on_message(&mut self, msg: &MavMessage, now: Duration) -> Step<()> {
        self.each(|c| Some(c.on_message(msg, now)))
    }

    fn on_timeout(&mut self, now: Duration) -> Step<()> {
        self.each(|c| (c.deadline() <= now).then(|| c.on_timeout(now)))
    }

    fn deadline(&self) -> Duration {
        self.commands
            .iter()
            .filter(|(_, a)| !*a)
            .map(|(c, _)| c.deadline())
            .min()
            .unwrap_or(Duration::ZERO)
    }

    fn retries(&self) -> u32 {
        self.commands.iter().map(|(c, _)| c.retries()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::wire::exchange::{RetryPolicy, Target, run_scripted};
    use mavlink::dialects::common::{COMMAND_ACK_DATA, MavCmd, MavResult};

    const T: Target = Target {
        system: 1,
        component: 1,
    };

    fn batch() -> AckedBatch {
        let p = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        AckedBatch::new(vec![
            AckedCommand::new(T, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, p, RetryPolicy::COMMAND),
            AckedCommand::new(T, MavCmd::MAV_CMD_MISSION_START, p, RetryPolicy::COMMAND),
        ])
    }

    fn ack(command: MavCmd, result: MavResult) -> MavMessage {
        MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command,
            result,
            ..COMMAND_ACK_DATA::DEFAULT
        })
    }

    fn command_of(m: &MavMessage) -> Option<MavCmd> {
        match m {
            MavMessage::COMMAND_LONG(c) => Some(c.command),
            _ => None,
        }
    }

    #[test]
    fn both_sent_at_once_and_done_when_both_are_accepted_a_lost_ack_resent_alone() {
        let mut lost_once = false;
        let (r, sent) = run_scripted(&mut batch(), Duration::from_millis(100), |m, _| {
            let c = command_of(m).expect("commands only");
            if c == MavCmd::MAV_CMD_MISSION_START && !lost_once {
                lost_once = true;
                return vec![];
            }
            vec![ack(c, MavResult::MAV_RESULT_ACCEPTED)]
        });
        assert_eq!(r, Ok(()));
        let order: Vec<MavCmd> = sent.iter().filter_map(command_of).collect();
        assert_eq!(
            order,
            [
                MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                MavCmd::MAV_CMD_MISSION_START,
                MavCmd::MAV_CMD_MISSION_START
            ],
            "both at the start, only the unanswered one again"
        );
    }

    #[test]
    fn a_refused_command_fails_the_batch() {
        let (r, _) = run_scripted(&mut batch(), Duration::from_millis(100), |m, _| {
            let c = command_of(m).expect("commands only");
            let result = if c == MavCmd::MAV_CMD_COMPONENT_ARM_DISARM {
                MavResult::MAV_RESULT_DENIED
            } else {
                MavResult::MAV_RESULT_ACCEPTED
            };
            vec![ack(c, result)]
        });
        assert!(
            matches!(
                r,
                Err(ProtocolError::CommandRefused {
                    command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                    ..
                })
            ),
            "{r:?}"
        );
    }
}
