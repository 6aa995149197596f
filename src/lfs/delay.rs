//! The motion model's control delay: the vehicle acts on the command of `delay` ticks ago, so the commands
//! not yet acted on wait in a queue. Kept apart from the loop so that changing the delay mid-flight (an
//! ensemble member's constants) keeps the vehicle moving.

use std::collections::VecDeque;

/// Commands given but not yet acted on, oldest first.
#[derive(Debug, Clone)]
pub struct DelayQueue<C> {
    pending: VecDeque<C>,
}

impl<C> Default for DelayQueue<C> {
    fn default() -> Self {
        Self {
            pending: VecDeque::new(),
        }
    }
}

impl<C: Copy> DelayQueue<C> {
    /// Queues `given` and returns what the vehicle acts on now with `delay` ticks of delay: `given` itself
    /// without delay, the command of `delay` ticks ago, or `hold` until there is one.
    pub fn act_on(&mut self, given: C, delay: usize, hold: C) -> C {
        if delay == 0 {
            return given;
        }
        self.pending.push_back(given);
        if self.pending.len() > delay {
            self.pending.pop_front().unwrap_or(hold)
        } else {
            hold
        }
    }

    /// Changes the delay from `old` to `new` ticks: a longer one repeats the oldest queued command (or
    /// `current`, the one acted on, when nothing was queued), a shorter one drops the oldest.
    pub fn resize(&mut self, old: usize, new: usize, current: C) {
        if old == new {
            return;
        }
        if old == 0 {
            self.pending = std::iter::repeat_n(current, new).collect();
        } else if new == 0 {
            self.pending.clear();
        } else {
            while self.pending.len() > new {
                self.pending.pop_front();
            }
            while self.pending.len() < new {
                let first = self.pending.front().copied().unwrap_or(current);
                self.pending.push_front(first);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_command_is_acted_on_delay_ticks_later_and_the_vehicle_holds_until_then() {
        let mut q = DelayQueue::default();
        let acted: Vec<i32> = (1..=5).map(|c| q.act_on(c, 2, 0)).collect();
        assert_eq!(acted, [0, 0, 1, 2, 3]);
        assert_eq!(DelayQueue::default().act_on(7, 0, 0), 7, "no delay, no queue");
    }

    #[test]
    fn a_longer_delay_repeats_the_oldest_and_a_shorter_one_drops_it() {
        let mut q = DelayQueue::default();
        for c in 1..=3 {
            q.act_on(c, 2, 0);
        }
        q.resize(2, 3, 1);
        assert_eq!(q.act_on(9, 3, 0), 2, "2 repeated at the front");
        q.resize(3, 1, 2);
        assert_eq!(q.act_on(10, 1, 0), 9);
        let mut fresh = DelayQueue::default();
        fresh.resize(0, 2, 5);
        assert_eq!(
            fresh.act_on(6, 2, 0),
            5,
            "from no delay: the current command fills the queue"
        );
    }
}
