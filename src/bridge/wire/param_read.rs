//! Reading one parameter (PARAM_REQUEST_READ -> PARAM_VALUE), bounded by retries; an unknown name ends early
//! on PX4's "unknown param" STATUSTEXT or after the retries.

use std::time::Duration;

use mavlink::dialects::common::{MavMessage, PARAM_REQUEST_READ_DATA};

use super::exchange::{Exchange, ProtocolError, RetryPolicy, Step, Target};
use super::params::decode;

/// Reads one parameter's value.
#[derive(Debug, Clone)]
pub struct ParamRead {
    target: Target,
    name: String,
    retry: RetryPolicy,
    retries: u32,
    deadline: Duration,
}

impl ParamRead {
    /// Reads `name` from `target`.
    pub fn new(target: Target, name: &str, retry: RetryPolicy) -> Self {
        Self {
            target,
            name: name.to_string(),
            retry,
            retries: 0,
            deadline: Duration::ZERO,
        }
    }

    fn request(&self) -> MavMessage {
        MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
            param_index: -1,
            target_system: self.target.system,
            target_component: self.target.component,
            param_id: self.name.as_str().into(),
        })
    }
}

impl Exchange for ParamRead {
    type Output = f64;

    fn start(&mut self, now: Duration) -> Vec<MavMessage> {
        self.deadline = now + self.retry.timeout;
        vec![self.request()]
    }

    fn on_message(&mut self, msg: &MavMessage, _now: Duration) -> Step<f64> {
        match msg {
            MavMessage::PARAM_VALUE(v) if v.param_id.to_str().ok() == Some(self.name.as_str()) => {
                Step::done(Ok(decode(v.param_value, v.param_type)))
            }
            MavMessage::STATUSTEXT(t) => {
                let text = t.text.to_str().unwrap_or("");
                if text.to_ascii_lowercase().contains("unknown param") && text.contains(self.name.as_str()) {
                    Step::done(Err(ProtocolError::UnknownParam {
                        name: self.name.clone(),
                    }))
                } else {
                    Step::wait()
                }
            }
            _ => Step::wait(),
        }
    }

    fn on_timeout(&mut self, now: Duration) -> Step<f64> {
        if self.retries >= self.retry.max_retries {
            // Silence is not a "no": a vehicle without the parameter says so (STATUSTEXT).
            return Step::done(Err(ProtocolError::Timeout {
                what: format!("reading parameter {}", self.name),
                retries: self.retries,
            }));
        }
        self.retries += 1;
        self.deadline = now + self.retry.timeout;
        Step::send(self.request())
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
    use mavlink::dialects::common::{MavParamType, PARAM_VALUE_DATA};

    const T: Target = Target {
        system: 1,
        component: 1,
    };

    fn value(name: &str, v: f32) -> MavMessage {
        MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
            param_value: v,
            param_count: 1,
            param_index: 0,
            param_id: name.into(),
            param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
        })
    }

    #[test]
    fn reads_after_a_lost_request_and_gives_up_on_silence() {
        let mut n = 0;
        let mut r = ParamRead::new(T, "MIS_DIST_1WP", RetryPolicy::PARAM);
        let (got, sent) = run_scripted(&mut r, Duration::from_millis(100), |m, _| {
            n += 1;
            match m {
                MavMessage::PARAM_REQUEST_READ(_) if n > 1 => vec![value("OTHER", 1.0), value("MIS_DIST_1WP", 900.0)],
                _ => vec![],
            }
        });
        assert_eq!(got, Ok(900.0));
        assert_eq!(sent.len(), 2, "one retry");
        let mut r = ParamRead::new(T, "NOPE", RetryPolicy::PARAM);
        let (got, sent) = run_scripted(&mut r, Duration::from_millis(100), |_, _| vec![]);
        assert_eq!(
            got,
            Err(ProtocolError::Timeout {
                what: "reading parameter NOPE".into(),
                retries: RetryPolicy::PARAM.max_retries
            })
        );
        assert_eq!(sent.len(), 1 + RetryPolicy::PARAM.max_retries as usize);
    }
}
