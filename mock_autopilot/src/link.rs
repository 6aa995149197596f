//! Fault injection between the vehicle and its transport: loss, duplication, latency, silence.
//!
//! Pure and seeded (ChaCha8Rng), with simulated time as input, so a fault run is repeatable for
//! a given seed and message sequence.

use std::collections::VecDeque;
use std::time::Duration;

use mavlink::MavHeader;
use mavlink::dialects::common::MavMessage;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// How long a simulated reboot keeps the link dead.
pub const REBOOT_DOWNTIME: Duration = Duration::from_secs(3);

/// Link faults; all times are simulated time.
#[derive(Debug, Clone, PartialEq)]
pub struct Faults {
    /// Seed of every random choice.
    pub seed: u64,
    /// Probability that a message (either direction) is dropped, 0..=1.
    pub loss: f64,
    /// Probability that a message (either direction) is delivered twice, 0..=1.
    pub duplicate: f64,
    /// One-way delay added in each direction.
    pub latency: Duration,
    /// The autopilot stops talking and listening after this time.
    pub silence_after: Option<Duration>,
    /// The autopilot reboots once at this time (link dead for `REBOOT_DOWNTIME`).
    pub reboot_after: Option<Duration>,
}

impl Default for Faults {
    fn default() -> Self {
        Self {
            seed: 0,
            loss: 0.0,
            duplicate: 0.0,
            latency: Duration::ZERO,
            silence_after: None,
            reboot_after: None,
        }
    }
}

/// Invalid fault settings.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FaultError {
    /// A probability outside 0..=1.
    #[error("{name} = {value}: a probability must be within 0..=1")]
    Probability {
        /// Flag name.
        name: &'static str,
        /// Value given.
        value: f64,
    },
}

impl Faults {
    /// Check the probabilities.
    pub fn validate(&self) -> Result<(), FaultError> {
        for (name, value) in [("loss", self.loss), ("duplicate", self.duplicate)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(FaultError::Probability { name, value });
            }
        }
        Ok(())
    }
}

/// Queues messages through the configured faults.
#[derive(Debug, Clone)]
pub struct FaultyLink {
    faults: Faults,
    rng: ChaCha8Rng,
    out_q: VecDeque<(Duration, MavMessage)>,
    in_q: VecDeque<(Duration, MavHeader, MavMessage)>,
    dead_until: Option<Duration>,
}

impl FaultyLink {
    /// A link with `faults` (assumed validated).
    pub fn new(faults: Faults) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(faults.seed),
            faults,
            out_q: VecDeque::new(),
            in_q: VecDeque::new(),
            dead_until: None,
        }
    }

    /// The fault settings.
    pub fn faults(&self) -> &Faults {
        &self.faults
    }

    /// True when nothing passes at `now` (silenced or rebooting).
    pub fn is_dead(&self, now: Duration) -> bool {
        self.faults.silence_after.is_some_and(|t| now >= t) || self.dead_until.is_some_and(|t| now < t)
    }

    /// Kill the link until `until` and drop everything in flight (a reboot).
    pub fn kill_until(&mut self, until: Duration) {
        self.dead_until = Some(until);
        self.out_q.clear();
        self.in_q.clear();
    }

    /// How many copies of a message survive loss and duplication (0, 1 or 2).
    fn copies(&mut self) -> usize {
        if self.faults.loss > 0.0 && self.rng.random_bool(self.faults.loss) {
            return 0;
        }
        if self.faults.duplicate > 0.0 && self.rng.random_bool(self.faults.duplicate) {
            2
        } else {
            1
        }
    }

    /// A message from the vehicle at `now`.
    pub fn outgoing(&mut self, now: Duration, msg: MavMessage) {
        if self.is_dead(now) {
            return;
        }
        let n = self.copies();
        let due = now + self.faults.latency;
        for _ in 0..n {
            self.out_q.push_back((due, msg.clone()));
        }
    }

    /// A message for the vehicle at `now`.
    pub fn incoming(&mut self, now: Duration, header: MavHeader, msg: MavMessage) {
        if self.is_dead(now) {
            return;
        }
        let n = self.copies();
        let due = now + self.faults.latency;
        for _ in 0..n {
            self.in_q.push_back((due, header, msg.clone()));
        }
    }

    /// Next outgoing message due at `now`.
    pub fn pop_outgoing(&mut self, now: Duration) -> Option<MavMessage> {
        if self.out_q.front().is_some_and(|(d, _)| *d <= now) {
            return self.out_q.pop_front().map(|(_, m)| m);
        }
        None
    }

    /// Next incoming message due at `now`.
    pub fn pop_incoming(&mut self, now: Duration) -> Option<(MavHeader, MavMessage)> {
        if self.in_q.front().is_some_and(|(d, _, _)| *d <= now) {
            return self.in_q.pop_front().map(|(_, h, m)| (h, m));
        }
        None
    }

    /// When the next queued message becomes due (for the runner's wake-up).
    pub fn next_due(&self) -> Option<Duration> {
        let a = self.out_q.front().map(|x| x.0);
        let b = self.in_q.front().map(|x| x.0);
        match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::ATTITUDE_DATA;

    fn msg(k: u32) -> MavMessage {
        MavMessage::ATTITUDE(ATTITUDE_DATA {
            time_boot_ms: k,
            ..Default::default()
        })
    }

    fn pass(faults: Faults, n: u32) -> Vec<u32> {
        let mut l = FaultyLink::new(faults);
        let mut got = Vec::new();
        for k in 0..n {
            let now = Duration::from_millis(u64::from(k));
            l.outgoing(now, msg(k));
            while let Some(MavMessage::ATTITUDE(a)) = l.pop_outgoing(now + Duration::from_secs(10)) {
                got.push(a.time_boot_ms);
            }
        }
        got
    }

    #[test]
    fn loss_and_duplicates_follow_probabilities_and_seed() {
        let lossy = Faults {
            loss: 0.3,
            seed: 7,
            ..Default::default()
        };
        let got = pass(lossy.clone(), 10_000);
        assert!((6_700..7_300).contains(&got.len()), "{}", got.len());
        assert_eq!(got, pass(lossy, 10_000), "same seed, same drops");
        let dup = Faults {
            duplicate: 0.5,
            seed: 1,
            ..Default::default()
        };
        let got = pass(dup, 10_000);
        assert!((14_500..15_500).contains(&got.len()));
        assert_eq!(pass(Faults::default(), 100), (0..100).collect::<Vec<_>>());
    }

    #[test]
    fn latency_silence_and_reboot() {
        let ms = Duration::from_millis;
        let mut l = FaultyLink::new(Faults {
            latency: ms(200),
            silence_after: Some(ms(1000)),
            ..Default::default()
        });
        l.outgoing(ms(0), msg(1));
        l.incoming(ms(0), MavHeader::default(), msg(2));
        assert!(l.pop_outgoing(ms(199)).is_none());
        assert_eq!(l.next_due(), Some(ms(200)));
        assert!(l.pop_outgoing(ms(200)).is_some());
        assert!(l.pop_incoming(ms(200)).is_some());
        l.outgoing(ms(1000), msg(3));
        l.incoming(ms(1000), MavHeader::default(), msg(4));
        assert!(l.pop_outgoing(ms(5000)).is_none() && l.pop_incoming(ms(5000)).is_none());
        let mut r = FaultyLink::new(Faults::default());
        r.outgoing(ms(0), msg(1));
        r.kill_until(ms(3000));
        assert!(
            r.pop_outgoing(ms(0)).is_none(),
            "in-flight messages die with the reboot"
        );
        assert!(r.is_dead(ms(2999)) && !r.is_dead(ms(3000)));
    }

    #[test]
    fn bad_probabilities_are_rejected() {
        assert!(
            Faults {
                loss: 1.5,
                ..Default::default()
            }
            .validate()
            .is_err()
        );
        assert!(
            Faults {
                duplicate: -0.1,
                ..Default::default()
            }
            .validate()
            .is_err()
        );
        assert!(
            Faults {
                loss: f64::NAN,
                ..Default::default()
            }
            .validate()
            .is_err()
        );
        assert!(Faults::default().validate().is_ok());
    }
}
