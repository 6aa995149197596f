//! Simulated time: PX4's clock in lockstep, counted in whole microseconds so that steps add up exactly.

use std::fmt;
use std::time::Duration;

/// An instant of simulated time, microseconds since the simulator started (time zero is before the first
/// step; the first sensor message is stamped one step later, never zero).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct SimTime(u64);

impl SimTime {
    /// Time zero.
    pub const ZERO: SimTime = SimTime(0);

    /// From microseconds.
    pub const fn from_micros(us: u64) -> Self {
        SimTime(us)
    }

    /// From milliseconds.
    pub const fn from_millis(ms: u64) -> Self {
        SimTime(ms * 1000)
    }

    /// From seconds (rounded to the microsecond; negative or NaN gives zero).
    pub fn from_secs_f64(s: f64) -> Self {
        SimTime((s * 1e6).round().max(0.0) as u64)
    }

    /// Microseconds.
    pub const fn as_micros(self) -> u64 {
        self.0
    }

    /// Seconds.
    pub fn as_secs_f64(self) -> f64 {
        self.0 as f64 * 1e-6
    }

    /// This instant plus a duration.
    pub fn plus(self, d: Duration) -> Self {
        SimTime(self.0.saturating_add(d.as_micros() as u64))
    }

    /// The duration from `earlier` to this instant (zero if `earlier` is later).
    pub fn since(self, earlier: SimTime) -> Duration {
        Duration::from_micros(self.0.saturating_sub(earlier.0))
    }
}

impl fmt::Display for SimTime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.3} s", self.as_secs_f64())
    }
}

/// The physics and sensor step: 4 ms, PX4's `IMU_INTEG_RATE` of 250 Hz and Gazebo's `max_step_size`.
pub const STEP: Duration = Duration::from_micros(4000);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_add_up_exactly() {
        let mut t = SimTime::ZERO;
        for _ in 0..250 {
            t = t.plus(STEP);
        }
        assert_eq!(t, SimTime::from_millis(1000));
        assert_eq!(t.since(SimTime::from_millis(996)), STEP);
        assert_eq!(SimTime::from_millis(1).since(t), Duration::ZERO);
        assert_eq!(SimTime::from_secs_f64(0.0125).as_micros(), 12_500);
    }
}

/// The simulated clock as the host reads it from another task or thread; clones share it.
#[derive(Debug, Clone, Default)]
pub struct SimClock(std::sync::Arc<std::sync::atomic::AtomicU64>);

impl SimClock {
    /// Simulated time now.
    pub fn now(&self) -> SimTime {
        SimTime(self.0.load(std::sync::atomic::Ordering::Acquire))
    }

    /// Moves the clock (the simulator does).
    pub(crate) fn set(&self, t: SimTime) {
        self.0.store(t.0, std::sync::atomic::Ordering::Release);
    }
}
