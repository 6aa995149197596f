//! The vehicle's latest poses, so the lockstep companion can plan from the pose of a latency ago, as the
//! real companion does from a camera frame that is already old.

use std::collections::VecDeque;
use std::time::Duration;

use crate::bridge::wire::pose::PoseNed;

/// Poses kept for the lockstep latency (2 s at 50 Hz).
const POSE_HISTORY: usize = 100;

/// The latest poses, to plan from an older one (lockstep latency).
#[derive(Debug, Default)]
pub(super) struct PoseHistory(VecDeque<PoseNed>);

impl PoseHistory {
    pub(super) fn push(&mut self, pose: Option<PoseNed>) {
        let Some(p) = pose else { return };
        if self.0.back().is_some_and(|last| last.time_boot_ms > p.time_boot_ms) {
            self.0.clear(); // a reboot
        }
        if self.0.len() == POSE_HISTORY {
            self.0.pop_front();
        }
        self.0.push_back(p);
    }

    /// The newest pose at or before vehicle time `t` (the oldest kept if all are newer).
    pub(super) fn at(&self, t: Duration) -> Option<PoseNed> {
        let ms = t.as_millis();
        self.0
            .iter()
            .rev()
            .find(|p| u128::from(p.time_boot_ms) <= ms)
            .or(self.0.front())
            .copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pose_history_gives_the_pose_a_latency_ago() {
        let pose = |ms: u32| PoseNed {
            time_boot_ms: ms,
            pos_ned: [f64::from(ms), 0.0, 0.0],
            vel_ned: [0.0; 3],
            yaw_rad: None,
        };
        let mut h = PoseHistory::default();
        assert_eq!(h.at(Duration::from_secs(1)), None);
        for ms in (1000..=3000).step_by(20) {
            h.push(Some(pose(ms)));
        }
        assert_eq!(h.0.len(), POSE_HISTORY, "bounded");
        let at = |ms: u64| h.at(Duration::from_millis(ms)).map(|p| p.time_boot_ms);
        assert_eq!(at(3000), Some(3000));
        assert_eq!(at(2999), Some(2980), "the newest at or before");
        assert_eq!(at(100), Some(1020), "older than kept: the oldest");
        h.push(Some(pose(40)));
        let at = |ms: u64| h.at(Duration::from_millis(ms)).map(|p| p.time_boot_ms);
        assert_eq!(at(3000), Some(40), "a reboot forgets the old boot's poses");
    }
}
