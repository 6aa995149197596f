//! The lockstep policy as a pure state machine on an injected wall clock: when to take the next step,
//! how long to wait for PX4's answer, when PX4 is lost. The TCP link asks it and does what it says.
//!
//! Before PX4's first HIL_ACTUATOR_CONTROLS the simulator freewheels: it steps by itself at
//! `freewheel_speed` times real time (PX4's start-up blocks until sensor time moves, and a flood of
//! sensor time would time PX4's start-up out). From the first answer on, each step waits for the answer
//! to the previous one, at most `actuator_wait` (then it steps anyway with the last command and counts a
//! timeout: PX4 skips an answer now and then), and never faster than `speed_cap` times real time if one is
//! set. A silence of `link_lost_after` once locked, or no answer at all within `first_answer_within`, ends
//! the run.

use std::time::{Duration, Instant};

use crate::time::STEP;

/// The lockstep figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LockstepConfig {
    /// The longest wait for PX4's answer to a step.
    pub actuator_wait: Duration,
    /// Silence from PX4 (once locked) after which the link counts as lost.
    pub link_lost_after: Duration,
    /// PX4 must answer within this (wall time) of connecting.
    pub first_answer_within: Duration,
    /// Real-time factor while freewheeling.
    pub freewheel_speed: f64,
    /// Highest real-time factor once locked (`None`: as fast as PX4 answers).
    pub speed_cap: Option<f64>,
}

impl Default for LockstepConfig {
    fn default() -> Self {
        Self {
            actuator_wait: Duration::from_millis(100),
            link_lost_after: Duration::from_secs(5),
            first_answer_within: Duration::from_secs(120),
            freewheel_speed: 1.0,
            speed_cap: None,
        }
    }
}

/// What to do now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decision {
    /// Take a step; `timed_out` if PX4 did not answer the previous one in time.
    Step {
        /// The wait for the answer ran out.
        timed_out: bool,
    },
    /// Nothing before this instant (or before a message arrives).
    WaitUntil(Instant),
    /// PX4 is gone: stop.
    LinkLost,
    /// PX4 connected but never answered.
    NeverAnswered,
}

/// Counters of a lockstep run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LockstepStats {
    /// Steps taken.
    pub steps: u64,
    /// Steps taken before the first answer.
    pub freewheel_steps: u64,
    /// Actuator messages received.
    pub answers: u64,
    /// Steps taken because the wait for an answer ran out.
    pub timeouts: u64,
}

/// The lockstep state.
#[derive(Debug, Clone)]
pub struct Lockstep {
    config: LockstepConfig,
    connected_at: Instant,
    locked: bool,
    answered: bool,
    sent_at: Option<Instant>,
    last_heard: Instant,
    next_due: Instant,
    stats: LockstepStats,
}

impl Lockstep {
    /// A link that connected at `now`.
    pub fn new(config: LockstepConfig, now: Instant) -> Self {
        Self {
            config,
            connected_at: now,
            locked: false,
            answered: false,
            sent_at: None,
            last_heard: now,
            next_due: now,
            stats: LockstepStats::default(),
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> LockstepStats {
        self.stats
    }

    /// Whether PX4 has answered once (lockstep proper).
    pub fn is_locked(&self) -> bool {
        self.locked
    }

    /// PX4 sent something at `now`.
    pub fn on_message(&mut self, now: Instant) {
        self.last_heard = now;
    }

    /// PX4 sent a motor command at `now`: the answer to the last step.
    pub fn on_actuators(&mut self, now: Instant) {
        self.last_heard = now;
        if !self.locked && self.config.speed_cap.is_none() {
            // The freewheel's pace no longer applies.
            self.next_due = now;
        }
        self.locked = true;
        self.answered = true;
        self.stats.answers += 1;
    }

    /// What to do at `now`.
    pub fn decide(&self, now: Instant) -> Decision {
        if !self.locked {
            if now.duration_since(self.connected_at) >= self.config.first_answer_within {
                return Decision::NeverAnswered;
            }
            return self.paced(now, false);
        }
        if now.duration_since(self.last_heard) >= self.config.link_lost_after {
            return Decision::LinkLost;
        }
        if self.answered || self.sent_at.is_none() {
            return self.paced(now, false);
        }
        let deadline = self.sent_at.map_or(now, |s| s + self.config.actuator_wait);
        if now >= deadline {
            self.paced(now, true)
        } else {
            Decision::WaitUntil(deadline.min(self.last_heard + self.config.link_lost_after))
        }
    }

    fn paced(&self, now: Instant, timed_out: bool) -> Decision {
        if now >= self.next_due {
            Decision::Step { timed_out }
        } else {
            Decision::WaitUntil(self.next_due)
        }
    }

    /// A step was taken (and its sensors sent) at `now`.
    pub fn stepped(&mut self, now: Instant, timed_out: bool) {
        self.stats.steps += 1;
        if !self.locked {
            self.stats.freewheel_steps += 1;
        }
        if timed_out {
            self.stats.timeouts += 1;
        }
        self.answered = false;
        self.sent_at = Some(now);
        let speed = if self.locked {
            self.config.speed_cap
        } else {
            Some(self.config.freewheel_speed)
        };
        self.next_due = match speed {
            Some(s) if s > 0.0 => {
                // Keep the average pace; after a stall of more than 50 ms start afresh instead of bursting.
                let next = self.next_due + STEP.div_f64(s);
                if next + Duration::from_millis(50) < now {
                    now
                } else {
                    next
                }
            }
            _ => now,
        };
    }
}

#[cfg(test)]
mod tests;
