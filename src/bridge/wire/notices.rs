//! What the vehicle says and what the bridge notices while a flight runs, kept for the report and handed to
//! an optional live sink (the `fly` CLI prints to stderr): the vehicle's STATUSTEXT of severity WARNING or
//! worse, readiness progress, and clock warnings.

use std::sync::{Arc, Mutex};

use mavlink::dialects::common::{MavMessage, MavSeverity};
use serde::Serialize;
use tokio::sync::broadcast;
use tokio::task::JoinHandle;

use super::clock::VehicleClock;
use super::link::Inbound;
use super::text_chunks::{Chunk, Joiner};

/// How long (vehicle time) a STATUSTEXT chunk waits for the next one before it is kept as it is.
const CHUNK_WAIT: std::time::Duration = std::time::Duration::from_secs(1);

/// One STATUSTEXT of severity WARNING or worse.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VehicleMessage {
    /// Bridge session time when it arrived, vehicle seconds.
    pub t_s: f64,
    /// `emergency`, `alert`, `critical`, `error` or `warning`.
    pub severity: &'static str,
    /// The vehicle's words.
    pub text: String,
}

/// Something to show the user as it happens.
#[derive(Debug, Clone, PartialEq)]
pub enum Notice {
    /// The vehicle said something (WARNING or worse).
    Vehicle(VehicleMessage),
    /// Waiting for the vehicle to become ready: what is missing, vehicle seconds waited.
    Waiting {
        /// What the vehicle still lacks, in words.
        missing: String,
        /// Vehicle seconds waited so far.
        waited_s: f64,
    },
    /// The vehicle's clock disagrees with the time scale.
    Clock(String),
    /// The vehicle that answered and was locked onto, in words, before anything is uploaded.
    Answered(String),
}

impl std::fmt::Display for Notice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Notice::Vehicle(m) => write!(f, "vehicle {} [{:.1} s]: {}", m.severity, m.t_s, m.text),
            Notice::Waiting { missing, waited_s } => {
                write!(f, "waiting for the vehicle ({waited_s:.0} s): {missing}")
            }
            Notice::Clock(w) => write!(f, "warning: {w}"),
            Notice::Answered(who) => write!(f, "vehicle answered: {who}"),
        }
    }
}

/// A live receiver of notices (e.g. the CLI printing them); shared, so cloning options is cheap.
#[derive(Clone)]
pub struct NoticeSink(pub Arc<dyn Fn(&Notice) + Send + Sync>);

impl NoticeSink {
    /// A sink calling `f`.
    pub fn new(f: impl Fn(&Notice) + Send + Sync + 'static) -> Self {
        Self(Arc::new(f))
    }
}

impl std::fmt::Debug for NoticeSink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("NoticeSink")
    }
}

impl PartialEq for NoticeSink {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Sends `n` to the sink, if any.
pub fn tell(sink: Option<&NoticeSink>, n: &Notice) {
    if let Some(s) = sink {
        (s.0)(n);
    }
}

/// MAVLink severity as a word; `None` for NOTICE and milder.
pub fn severity_word(s: MavSeverity) -> Option<&'static str> {
    use MavSeverity::*;
    Some(match s {
        MAV_SEVERITY_EMERGENCY => "emergency",
        MAV_SEVERITY_ALERT => "alert",
        MAV_SEVERITY_CRITICAL => "critical",
        MAV_SEVERITY_ERROR => "error",
        MAV_SEVERITY_WARNING => "warning",
        _ => return None,
    })
}

/// The vehicle's messages so far, shared between the collecting task and the session.
pub type Messages = Arc<Mutex<Vec<VehicleMessage>>>;

/// `texts` with each text once, in the order it first came, a repeated one followed by its count: a vehicle
/// that refuses 96 times says "Arming denied (x96)", not the words 96 times over.
pub fn counted<'a>(texts: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let mut seen: Vec<(&str, usize)> = Vec::new();
    for t in texts {
        match seen.iter_mut().find(|(s, _)| *s == t) {
            Some((_, n)) => *n += 1,
            None => seen.push((t, 1)),
        }
    }
    (seen.into_iter())
        .map(|(t, n)| if n > 1 { format!("{t} (x{n})") } else { t.to_string() })
        .collect()
}

/// The last `n` messages' texts joined with "; " (what a refusal's reason quotes), repeats counted.
pub fn last_texts(messages: &Messages, n: usize) -> Option<String> {
    let m = messages.lock().unwrap_or_else(|p| p.into_inner());
    let start = m.len().saturating_sub(n);
    let texts = counted(m[start..].iter().map(|v| v.text.as_str()));
    (!texts.is_empty()).then(|| texts.join("; "))
}

/// Number of messages so far (to quote only those after some point).
pub fn count(messages: &Messages) -> usize {
    messages.lock().map_or(0, |m| m.len())
}

/// Texts of the messages from index `from` on, joined with "; ", repeats counted ([`counted`]).
pub fn texts_since(messages: &Messages, from: usize) -> Option<String> {
    let m = messages.lock().unwrap_or_else(|p| p.into_inner());
    let texts = counted(m.iter().skip(from).map(|v| v.text.as_str()));
    (!texts.is_empty()).then(|| texts.join("; "))
}

/// Collects every STATUSTEXT of severity WARNING or worse from `rx` into `out` (and the sink) until aborted.
pub fn spawn_collector(
    mut rx: broadcast::Receiver<Arc<Inbound>>,
    clock: VehicleClock,
    out: Messages,
    sink: Option<NoticeSink>,
) -> JoinHandle<()> {
    tokio::spawn(async move {
        let mut joiner = Joiner::default();
        let keep = |(severity, text): (MavSeverity, String)| {
            let Some(severity) = severity_word(severity) else {
                return;
            };
            let m = VehicleMessage {
                t_s: clock.now().as_secs_f64(),
                severity,
                text: text.trim_end().to_string(),
            };
            tell(sink.as_ref(), &Notice::Vehicle(m.clone()));
            out.lock().unwrap_or_else(|p| p.into_inner()).push(m);
        };
        loop {
            // A text waiting for its next chunk is kept as it is when none comes in time.
            let next = if joiner.waiting() {
                match tokio::time::timeout(clock.wall(CHUNK_WAIT), rx.recv()).await {
                    Ok(r) => r,
                    Err(_) => {
                        joiner.flush().into_iter().for_each(keep);
                        continue;
                    }
                }
            } else {
                rx.recv().await
            };
            match next {
                Ok(inb) => {
                    let MavMessage::STATUSTEXT(t) = &inb.msg else { continue };
                    let Some(chunk) = Chunk::of(t) else { continue };
                    joiner.feed(chunk).into_iter().for_each(keep);
                }
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => {
                    joiner.flush().into_iter().for_each(keep);
                    return;
                }
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn severities_and_texts() {
        assert_eq!(severity_word(MavSeverity::MAV_SEVERITY_CRITICAL), Some("critical"));
        assert_eq!(severity_word(MavSeverity::MAV_SEVERITY_INFO), None);
        let m: Messages = Arc::default();
        assert_eq!(last_texts(&m, 3), None);
        for t in ["a", "b", "c"] {
            m.lock().unwrap().push(VehicleMessage {
                t_s: 0.0,
                severity: "warning",
                text: t.into(),
            });
        }
        assert_eq!(last_texts(&m, 2).as_deref(), Some("b; c"));
        assert_eq!(texts_since(&m, 1).as_deref(), Some("b; c"));
        assert_eq!(texts_since(&m, 3), None);
        let n = Notice::Vehicle(m.lock().unwrap()[0].clone());
        assert_eq!(n.to_string(), "vehicle warning [0.0 s]: a");
        let a = NoticeSink::new(|_| {});
        assert_eq!(a, a.clone());
        assert_ne!(a, NoticeSink::new(|_| {}));
    }

    #[test]
    fn a_refusal_repeated_96_times_is_said_once_with_its_count() {
        let m: Messages = Arc::default();
        let push = |t: &str| {
            m.lock().unwrap().push(VehicleMessage {
                t_s: 0.0,
                severity: "critical",
                text: t.into(),
            })
        };
        push("Preflight Fail: baro");
        for _ in 0..96 {
            push("Arming denied: Resolve system health failures first");
        }
        let line = texts_since(&m, 0).unwrap();
        assert_eq!(
            line,
            "Preflight Fail: baro; Arming denied: Resolve system health failures first (x96)"
        );
        assert_eq!(
            last_texts(&m, 2).unwrap(),
            "Arming denied: Resolve system health failures first (x2)"
        );
    }
}
