//! How many of a flight's avoidance answers came from the planner and how many mirrored PX4's own setpoint
//! because no plan was ready in time. A mirrored answer flies PX4's setpoint straight on, without avoidance:
//! a flight where that happens often measures how loaded the machine was, not how the vehicle avoids.

use serde::Serialize;

/// Above this share of mirrored answers a flight is starved. Of 235 PX4 v1.14 SIH flights on 2 cores, 14
/// went over it, all while a compiler or a fourth job ran, and 7 of those flew into a box, against 3
/// collisions in the other 221 (docs/px4.md).
pub const STARVED_SHARE: f64 = 0.01;

/// The answers of one flight's companion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct AnswerCounts {
    /// Answers from the planner.
    pub planned: u64,
    /// Answers that mirrored PX4's setpoint.
    pub mirrored: u64,
}

impl AnswerCounts {
    /// All answers sent.
    pub fn total(&self) -> u64 {
        self.planned + self.mirrored
    }

    /// More than [`STARVED_SHARE`] of the answers mirrored (the very first one, sent before any plan exists,
    /// always does and is not counted against the flight).
    pub fn starved(&self) -> bool {
        self.mirrored > 1 && self.mirrored as f64 > STARVED_SHARE * self.total() as f64
    }

    /// The sentence saying so.
    pub fn describe(&self) -> String {
        format!(
            "{} of {} avoidance answers mirrored PX4's own setpoint (no plan in time)",
            self.mirrored,
            self.total()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn starved_above_one_percent_not_counting_the_first_answer() {
        let c = |planned, mirrored| AnswerCounts { planned, mirrored };
        assert!(!c(0, 1).starved(), "the first answer before any plan");
        assert!(!c(700, 7).starved(), "exactly 1 %");
        assert!(c(700, 8).starved());
        assert!(c(1569, 146).starved());
        assert_eq!(
            c(700, 40).describe(),
            "40 of 740 avoidance answers mirrored PX4's own setpoint (no plan in time)"
        );
    }
}
