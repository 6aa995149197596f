//! The shape every request/response protocol takes here: a socket-free state machine fed messages and
//! timeouts in vehicle time, returning what to send and, at the end, its outcome. One async driver
//! ([`crate::bridge::wire::link::Link::exchange`]) runs any of them; tests script them with a fake clock.

use std::time::Duration;

use mavlink::dialects::common::{MavCmd, MavMessage, MavMissionResult, MavMissionType, MavResult};

/// The vehicle's MAVLink address that requests go to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Target {
    /// System id.
    pub system: u8,
    /// Component id (1 = autopilot).
    pub component: u8,
}

/// How long to wait for an answer and how often to retry, in vehicle time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetryPolicy {
    /// Wait this long for each answer.
    pub timeout: Duration,
    /// Resend at most this many times in a row without progress.
    pub max_retries: u32,
}

impl RetryPolicy {
    /// Retries in a row for every exchange. At 20 % loss each way a round trip fails 36 % of the time, so the
    /// MAVLink protocols' customary 5 retries lose one exchange in 460 and a flight's ~40 exchanges fail 1 setup
    /// in 12 (measured: 1 in 25 mock flights); 10 lose one in 78 000. The price: a vehicle that falls silent
    /// during setup is declared lost after 11 timeouts instead of 6.
    const IN_A_ROW: u32 = 10;
    /// The mission protocol (1.5 s per answer, as the MAVLink spec).
    pub const MISSION: RetryPolicy = RetryPolicy {
        timeout: Duration::from_millis(1500),
        max_retries: Self::IN_A_ROW,
    };
    /// Commands (1 s per answer, as MAVSDK).
    pub const COMMAND: RetryPolicy = RetryPolicy {
        timeout: Duration::from_millis(1000),
        max_retries: Self::IN_A_ROW,
    };
    /// Parameters (1 s per answer).
    pub const PARAM: RetryPolicy = RetryPolicy {
        timeout: Duration::from_millis(1000),
        max_retries: Self::IN_A_ROW,
    };
}

/// Why a protocol exchange failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProtocolError {
    /// No answer after every retry.
    #[error("{what}: no answer from the vehicle after {retries} retries")]
    Timeout {
        /// What was being done.
        what: String,
        /// Retries made.
        retries: u32,
    },
    /// The vehicle answered a mission transfer with an error MISSION_ACK.
    #[error("the vehicle refused the {} upload: {} ({})", mission_type_name(*.mission_type), *.result as u32, explain_mission_result(*.result))]
    MissionRefused {
        /// Mission, fence or rally.
        mission_type: MavMissionType,
        /// The MISSION_ACK code.
        result: MavMissionResult,
    },
    /// The vehicle answered a command with an error COMMAND_ACK.
    #[error("the vehicle refused {command:?}: {result:?} ({})", explain_command_result(*.result))]
    CommandRefused {
        /// The command.
        command: MavCmd,
        /// The COMMAND_ACK result.
        result: MavResult,
    },
    /// The vehicle has no parameter of this name.
    #[error("the vehicle has no parameter {name:?}")]
    UnknownParam {
        /// The name.
        name: String,
    },
    /// A parameter read back with another value than was set.
    #[error("parameter {name} reads back as {got} after setting {wanted}")]
    ParamMismatch {
        /// The name.
        name: String,
        /// Value set.
        wanted: f64,
        /// Value read back.
        got: f64,
    },
    /// The mission read back differs from the one uploaded.
    #[error("the mission read back from the vehicle differs from the upload: {0}")]
    MissionMismatch(String),
    /// The caller cancelled.
    #[error("cancelled")]
    Cancelled,
}

fn mission_type_name(t: MavMissionType) -> &'static str {
    match t {
        MavMissionType::MAV_MISSION_TYPE_MISSION => "mission",
        MavMissionType::MAV_MISSION_TYPE_FENCE => "geofence",
        MavMissionType::MAV_MISSION_TYPE_RALLY => "rally point",
        _ => "plan",
    }
}

/// A sentence for every MAV_MISSION_RESULT code.
pub fn explain_mission_result(r: MavMissionResult) -> &'static str {
    use MavMissionResult::*;
    match r {
        MAV_MISSION_ACCEPTED => "accepted",
        MAV_MISSION_ERROR => "generic error (PX4: busy, or a fence/rally command inside a mission)",
        MAV_MISSION_UNSUPPORTED_FRAME => "a coordinate frame is not supported (PX4 wants global frames)",
        MAV_MISSION_UNSUPPORTED => "a command is not supported by this vehicle",
        MAV_MISSION_NO_SPACE => "too many items for the vehicle's storage",
        MAV_MISSION_INVALID => "an item parameter is invalid",
        MAV_MISSION_INVALID_PARAM1 => "param1 of an item is invalid",
        MAV_MISSION_INVALID_PARAM2 => "param2 of an item is invalid",
        MAV_MISSION_INVALID_PARAM3 => "param3 of an item is invalid",
        MAV_MISSION_INVALID_PARAM4 => "param4 of an item is invalid",
        MAV_MISSION_INVALID_PARAM5_X => "x / latitude of an item is invalid",
        MAV_MISSION_INVALID_PARAM6_Y => "y / longitude of an item is invalid",
        MAV_MISSION_INVALID_PARAM7 => "z / altitude of an item is invalid",
        MAV_MISSION_INVALID_SEQUENCE => "items arrived out of sequence",
        MAV_MISSION_DENIED => "the vehicle is not accepting plans now (e.g. flying)",
        MAV_MISSION_OPERATION_CANCELLED => "the vehicle cancelled the transfer",
    }
}

/// A sentence for every MAV_RESULT code.
pub fn explain_command_result(r: MavResult) -> &'static str {
    use MavResult::*;
    match r {
        MAV_RESULT_ACCEPTED => "accepted",
        MAV_RESULT_TEMPORARILY_REJECTED => "not possible in the vehicle's current state (see its STATUSTEXT)",
        MAV_RESULT_DENIED => "denied (invalid parameters or not allowed)",
        MAV_RESULT_UNSUPPORTED => "not supported by this vehicle",
        MAV_RESULT_FAILED => "tried and failed",
        MAV_RESULT_IN_PROGRESS => "in progress",
        MAV_RESULT_CANCELLED => "cancelled",
        #[allow(unreachable_patterns)]
        _ => "unknown result",
    }
}

/// What one input to an exchange produced.
#[derive(Debug, Clone, PartialEq)]
pub struct Step<T> {
    /// Messages to send now, in order.
    pub send: Vec<MavMessage>,
    /// The outcome, once the exchange is over.
    pub done: Option<Result<T, ProtocolError>>,
}

impl<T> Step<T> {
    /// Nothing to do.
    pub fn wait() -> Self {
        Self {
            send: Vec::new(),
            done: None,
        }
    }

    /// Send `msg` and keep going.
    pub fn send(msg: MavMessage) -> Self {
        Self {
            send: vec![msg],
            done: None,
        }
    }

    /// Finished with `outcome`.
    pub fn done(outcome: Result<T, ProtocolError>) -> Self {
        Self {
            send: Vec::new(),
            done: Some(outcome),
        }
    }

    /// Send `msg`, then finish with `outcome`.
    pub fn send_then(msg: MavMessage, outcome: Result<T, ProtocolError>) -> Self {
        Self {
            send: vec![msg],
            done: Some(outcome),
        }
    }
}

/// A request/response protocol as a pure state machine; times are vehicle time.
pub trait Exchange {
    /// The result on success.
    type Output;
    /// The first messages to send.
    fn start(&mut self, now: Duration) -> Vec<MavMessage>;
    /// A message from the vehicle.
    fn on_message(&mut self, msg: &MavMessage, now: Duration) -> Step<Self::Output>;
    /// Called once `now >= deadline()`.
    fn on_timeout(&mut self, now: Duration) -> Step<Self::Output>;
    /// When to call [`Exchange::on_timeout`].
    fn deadline(&self) -> Duration;
    /// Messages re-sent so far (for the link statistics).
    fn retries(&self) -> u32;
}

/// Runs an exchange against a scripted vehicle (`respond` maps each sent message to replies), advancing a fake
/// clock by `tick` whenever nothing is pending; for unit tests.
#[cfg(test)]
pub fn run_scripted<E: Exchange>(
    ex: &mut E,
    tick: Duration,
    mut respond: impl FnMut(&MavMessage, Duration) -> Vec<MavMessage>,
) -> (Result<E::Output, ProtocolError>, Vec<MavMessage>) {
    let mut now = Duration::ZERO;
    let mut sent = Vec::new();
    let mut inbox: std::collections::VecDeque<MavMessage> = Default::default();
    let outgoing = ex.start(now);
    for m in outgoing {
        inbox.extend(respond(&m, now));
        sent.push(m);
    }
    for _ in 0..100_000 {
        let step = match inbox.pop_front() {
            Some(m) => ex.on_message(&m, now),
            None => {
                now = ex.deadline().max(now + tick);
                ex.on_timeout(now)
            }
        };
        for m in step.send {
            inbox.extend(respond(&m, now));
            sent.push(m);
        }
        if let Some(done) = step.done {
            return (done, sent);
        }
    }
    panic!("scripted exchange did not finish");
}
