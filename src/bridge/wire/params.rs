//! Setting PX4 parameters and reading them back, as a socket-free state machine. Each parameter is first read
//! (to learn the type PX4 declares and the old value, so it can be restored), then set with that type, then
//! confirmed by the PARAM_VALUE echo. PX4 encodes integers bytewise: the i32's bits travel in the f32 field.

use std::time::Duration;

use mavlink::dialects::common::{MavMessage, MavParamType, PARAM_REQUEST_READ_DATA, PARAM_SET_DATA};

use super::exchange::{Exchange, ProtocolError, RetryPolicy, Step, Target};

/// Whether a MAVLink parameter type holds an integer (bytewise-encoded by PX4).
pub fn is_int(t: MavParamType) -> bool {
    use MavParamType::*;
    matches!(
        t,
        MAV_PARAM_TYPE_UINT8
            | MAV_PARAM_TYPE_INT8
            | MAV_PARAM_TYPE_UINT16
            | MAV_PARAM_TYPE_INT16
            | MAV_PARAM_TYPE_UINT32
            | MAV_PARAM_TYPE_INT32
    )
}

/// The value of a PARAM_VALUE / PARAM_SET field as a number, decoding integers bytewise.
pub fn decode(wire: f32, t: MavParamType) -> f64 {
    if is_int(t) {
        f64::from(wire.to_bits() as i32)
    } else {
        f64::from(wire)
    }
}

/// The wire field for `value` of type `t` (integers rounded and bytewise-encoded).
pub fn encode(value: f64, t: MavParamType) -> f32 {
    if is_int(t) {
        f32::from_bits(value.round() as i32 as u32)
    } else {
        value as f32
    }
}

fn same(a: f64, b: f64, t: MavParamType) -> bool {
    if is_int(t) {
        a.round() == b.round()
    } else {
        (a - b).abs() <= 1e-6 * a.abs().max(1.0)
    }
}

/// One parameter after the exchange.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamChange {
    /// Name.
    pub name: String,
    /// Value before.
    pub old: f64,
    /// Value now (read back).
    pub new: f64,
    /// Type the vehicle declares.
    pub param_type: MavParamType,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    Reading,
    Setting { param_type: MavParamType, old: f64 },
}

/// Sets parameters one after the other and reads each back.
#[derive(Debug, Clone)]
pub struct ParamSet {
    target: Target,
    wanted: Vec<(String, f64)>,
    index: usize,
    phase: Phase,
    last_seen: Option<f64>,
    done: Vec<ParamChange>,
    retry: RetryPolicy,
    in_a_row: u32,
    retries: u32,
    deadline: Duration,
}

impl ParamSet {
    /// Sets `wanted` (name, value) in order on `target`.
    pub fn new(target: Target, wanted: Vec<(String, f64)>, retry: RetryPolicy) -> Self {
        Self {
            target,
            wanted,
            index: 0,
            phase: Phase::Reading,
            last_seen: None,
            done: Vec::new(),
            retry,
            in_a_row: 0,
            retries: 0,
            deadline: Duration::ZERO,
        }
    }

    fn name(&self) -> &str {
        self.wanted.get(self.index).map_or("", |(n, _)| n.as_str())
    }

    fn current_msg(&self) -> Option<MavMessage> {
        let (name, value) = self.wanted.get(self.index)?;
        Some(match self.phase {
            Phase::Reading => MavMessage::PARAM_REQUEST_READ(PARAM_REQUEST_READ_DATA {
                param_index: -1,
                target_system: self.target.system,
                target_component: self.target.component,
                param_id: name.as_str().into(),
            }),
            Phase::Setting { param_type, .. } => MavMessage::PARAM_SET(PARAM_SET_DATA {
                param_value: encode(*value, param_type),
                target_system: self.target.system,
                target_component: self.target.component,
                param_id: name.as_str().into(),
                param_type,
            }),
        })
    }

    fn advance(&mut self, now: Duration) -> Step<Vec<ParamChange>> {
        self.in_a_row = 0;
        self.last_seen = None;
        self.deadline = now + self.retry.timeout;
        match self.current_msg() {
            Some(m) => Step::send(m),
            None => Step::done(Ok(std::mem::take(&mut self.done))),
        }
    }
}

impl Exchange for ParamSet {
    type Output = Vec<ParamChange>;

    fn start(&mut self, now: Duration) -> Vec<MavMessage> {
        self.deadline = now + self.retry.timeout;
        self.current_msg().into_iter().collect()
    }

    fn on_message(&mut self, msg: &MavMessage, now: Duration) -> Step<Self::Output> {
        match msg {
            MavMessage::PARAM_VALUE(v) if v.param_id.to_str().ok() == Some(self.name()) => {
                let got = decode(v.param_value, v.param_type);
                let (name, wanted) = self.wanted[self.index].clone();
                match self.phase {
                    Phase::Reading => {
                        self.phase = Phase::Setting {
                            param_type: v.param_type,
                            old: got,
                        };
                        self.advance(now)
                    }
                    Phase::Setting { param_type, old } => {
                        if same(got, wanted, param_type) {
                            self.done.push(ParamChange {
                                name,
                                old,
                                new: got,
                                param_type,
                            });
                            self.index += 1;
                            self.phase = Phase::Reading;
                            self.advance(now)
                        } else {
                            // Maybe a late echo of our read: wait; the retry decides.
                            self.last_seen = Some(got);
                            Step::wait()
                        }
                    }
                }
            }
            // PX4 and the mock say so in a STATUSTEXT ("[pm] unknown param: NAME").
            MavMessage::STATUSTEXT(t) => {
                let text = t.text.to_str().unwrap_or("");
                if text.to_ascii_lowercase().contains("unknown param") && text.contains(self.name()) {
                    Step::done(Err(ProtocolError::UnknownParam {
                        name: self.name().to_string(),
                    }))
                } else {
                    Step::wait()
                }
            }
            _ => Step::wait(),
        }
    }

    fn on_timeout(&mut self, now: Duration) -> Step<Self::Output> {
        if self.in_a_row >= self.retry.max_retries {
            let name = self.name().to_string();
            return Step::done(Err(match (self.phase, self.last_seen) {
                (Phase::Setting { .. }, Some(got)) => ProtocolError::ParamMismatch {
                    wanted: self.wanted[self.index].1,
                    name,
                    got,
                },
                // Silence is not a "no": a vehicle without the parameter says so (STATUSTEXT).
                (Phase::Reading, _) => ProtocolError::Timeout {
                    what: format!("reading parameter {name}"),
                    retries: self.in_a_row,
                },
                _ => ProtocolError::Timeout {
                    what: format!("setting parameter {name}"),
                    retries: self.in_a_row,
                },
            }));
        }
        self.in_a_row += 1;
        self.retries += 1;
        self.deadline = now + self.retry.timeout;
        match self.current_msg() {
            Some(m) => Step::send(m),
            None => Step::done(Ok(std::mem::take(&mut self.done))),
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
    use mavlink::dialects::common::{MavSeverity, PARAM_VALUE_DATA, STATUSTEXT_DATA};
    use std::collections::HashMap;

    const T: Target = Target {
        system: 1,
        component: 1,
    };

    /// A PX4-like table: NAV_ACC_RAD float, GF_ACTION int; SET to a value outside `limits` is ignored.
    fn vehicle(mut drop: impl FnMut(usize) -> bool) -> impl FnMut(&MavMessage, Duration) -> Vec<MavMessage> {
        let mut table: HashMap<&str, (f32, MavParamType)> = HashMap::from([
            ("NAV_ACC_RAD", (2.0, MavParamType::MAV_PARAM_TYPE_REAL32)),
            ("GF_ACTION", (f32::from_bits(2), MavParamType::MAV_PARAM_TYPE_INT32)),
        ]);
        let mut k = 0;
        move |m, _| {
            k += 1;
            if drop(k) {
                return vec![];
            }
            let name = match m {
                MavMessage::PARAM_REQUEST_READ(r) => r.param_id.to_str().unwrap_or("").to_string(),
                MavMessage::PARAM_SET(s) => {
                    let n = s.param_id.to_str().unwrap_or("").to_string();
                    let v = decode(s.param_value, s.param_type);
                    if let Some(e) = table.get_mut(n.as_str())
                        && v < 100.0
                    {
                        e.0 = s.param_value;
                    }
                    n
                }
                _ => return vec![],
            };
            match table.get(name.as_str()) {
                Some(&(v, t)) => vec![MavMessage::PARAM_VALUE(PARAM_VALUE_DATA {
                    param_value: v,
                    param_count: 2,
                    param_index: 0,
                    param_id: name.as_str().into(),
                    param_type: t,
                })],
                None => vec![MavMessage::STATUSTEXT(STATUSTEXT_DATA {
                    severity: MavSeverity::MAV_SEVERITY_ERROR,
                    text: format!("[pm] unknown param: {name}").as_str().into(),
                    id: 0,
                    chunk_seq: 0,
                })],
            }
        }
    }

    fn set(list: &[(&str, f64)], drop: impl FnMut(usize) -> bool) -> (Result<Vec<ParamChange>, ProtocolError>, u32) {
        let wanted = list.iter().map(|(n, v)| (n.to_string(), *v)).collect();
        let mut p = ParamSet::new(T, wanted, RetryPolicy::PARAM);
        let (r, _) = run_scripted(&mut p, Duration::from_millis(10), vehicle(drop));
        (r, p.retries())
    }

    #[test]
    fn sets_floats_and_bytewise_ints() {
        let (r, retries) = set(&[("NAV_ACC_RAD", 0.5), ("GF_ACTION", 1.0)], |_| false);
        let r = r.unwrap();
        assert_eq!(retries, 0);
        assert_eq!((r[0].old, r[0].new), (2.0, 0.5));
        assert_eq!((r[1].old, r[1].new), (2.0, 1.0));
        assert_eq!(r[1].param_type, MavParamType::MAV_PARAM_TYPE_INT32);
        assert_eq!(encode(1.0, MavParamType::MAV_PARAM_TYPE_INT32).to_bits(), 1);
        assert_eq!(
            decode(
                encode(-3.0, MavParamType::MAV_PARAM_TYPE_INT32),
                MavParamType::MAV_PARAM_TYPE_INT32
            ),
            -3.0
        );
    }

    #[test]
    fn lossy_link_still_sets() {
        let (r, retries) = set(&[("NAV_ACC_RAD", 0.5), ("GF_ACTION", 1.0)], |k| k % 2 == 0);
        assert_eq!(r.unwrap().len(), 2);
        assert!(retries >= 2);
    }

    #[test]
    fn unknown_refused_and_silent() {
        let (r, _) = set(&[("NO_SUCH_PARAM", 1.0)], |_| false);
        assert_eq!(
            r.unwrap_err().to_string(),
            "the vehicle has no parameter \"NO_SUCH_PARAM\""
        );
        let (r, _) = set(&[("NAV_ACC_RAD", 500.0)], |_| false);
        assert!(matches!(r, Err(ProtocolError::ParamMismatch { got: 2.0, .. })), "{r:?}");
        let mut p = ParamSet::new(T, vec![("X".into(), 1.0)], RetryPolicy::PARAM);
        let (r, sent) = run_scripted(&mut p, Duration::from_millis(10), |_, _| vec![]);
        let e = r.unwrap_err().to_string();
        assert!(
            e.contains("reading parameter X: no answer"),
            "a silence is a timeout: {e}"
        );
        assert_eq!(sent.len(), 1 + RetryPolicy::PARAM.max_retries as usize);
    }
}
