//! Simulated time and how it is paced against wall time (`--speed-factor`).
//!
//! Every timer in the mock runs on simulated time, which advances only in fixed physics steps,
//! so a run is repeatable; the pacer only decides how many steps fit in the wall time so far.

use std::time::{Duration, Instant};

/// The largest speed-up parsed: a 4 ms physics step then still lasts 4 µs of wall time; far beyond it the
/// pacing arithmetic degenerates (`max` is the way to ask for no pacing).
pub const MAX_SPEED_FACTOR: f64 = 1000.0;

/// How fast simulated time runs relative to wall time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpeedFactor {
    /// Simulated time runs K times faster than wall time (K > 0, finite).
    Times(f64),
    /// No pacing: step as fast as the CPU allows (clients must answer within simulated timeouts,
    /// so this suits in-process use and very fast clients).
    AsFastAsPossible,
}

impl SpeedFactor {
    /// Parse "K" (a positive number) or "max".
    pub fn parse(s: &str) -> Result<Self, String> {
        if s.eq_ignore_ascii_case("max") {
            return Ok(Self::AsFastAsPossible);
        }
        match s.parse::<f64>() {
            Ok(k) if k.is_finite() && k > 0.0 && k <= MAX_SPEED_FACTOR => Ok(Self::Times(k)),
            _ => Err(format!(
                "speed factor {s:?}: expected a number above 0 and at most {MAX_SPEED_FACTOR}, or \"max\""
            )),
        }
    }
}

impl Default for SpeedFactor {
    fn default() -> Self {
        Self::Times(1.0)
    }
}

/// Paces fixed simulation steps against the wall clock.
#[derive(Debug, Clone)]
pub struct Pacer {
    speed: SpeedFactor,
    start: Instant,
    step: Duration,
}

impl Pacer {
    /// A pacer starting now.
    pub fn new(speed: SpeedFactor, step: Duration, start: Instant) -> Self {
        Self { speed, start, step }
    }

    /// The fixed simulation step.
    pub fn step(&self) -> Duration {
        self.step
    }

    /// The simulated time the simulation may reach at `wall_now` (None: unbounded).
    pub fn sim_target(&self, wall_now: Instant) -> Option<Duration> {
        match self.speed {
            SpeedFactor::Times(k) => Some(wall_now.saturating_duration_since(self.start).mul_f64(k)),
            SpeedFactor::AsFastAsPossible => None,
        }
    }

    /// Forget pacing credit beyond `max_lag`: after simulated time stood still (a lockstep wait), the
    /// simulation may catch up at most `max_lag` unpaced instead of racing through every protocol timer.
    pub fn limit_lag(&mut self, sim_now: Duration, wall_now: Instant, max_lag: Duration) {
        if let SpeedFactor::Times(k) = self.speed
            && self.sim_target(wall_now).is_some_and(|t| t > sim_now + max_lag)
        {
            let ahead = (sim_now + max_lag).div_f64(k);
            self.start = wall_now.checked_sub(ahead).unwrap_or(self.start);
        }
    }

    /// The wall instant at which simulated time `sim` is due (None: immediately).
    pub fn wall_due(&self, sim: Duration) -> Option<Instant> {
        match self.speed {
            SpeedFactor::Times(k) => Some(self.start + sim.div_f64(k)),
            SpeedFactor::AsFastAsPossible => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_speed() {
        assert_eq!(SpeedFactor::parse("max"), Ok(SpeedFactor::AsFastAsPossible));
        assert_eq!(SpeedFactor::parse("20"), Ok(SpeedFactor::Times(20.0)));
        assert!(SpeedFactor::parse("0").is_err());
        assert!(SpeedFactor::parse("-1").is_err());
        assert!(SpeedFactor::parse("inf").is_err());
        assert!(SpeedFactor::parse("1e300").is_err());
        assert_eq!(SpeedFactor::parse("1000"), Ok(SpeedFactor::Times(1000.0)));
        assert!(SpeedFactor::parse("x").is_err());
    }

    #[test]
    fn pacing_scales_time() {
        let t0 = Instant::now();
        let p = Pacer::new(SpeedFactor::Times(10.0), Duration::from_millis(4), t0);
        assert_eq!(
            p.sim_target(t0 + Duration::from_millis(100)),
            Some(Duration::from_secs(1))
        );
        assert_eq!(
            p.wall_due(Duration::from_secs(1)),
            Some(t0 + Duration::from_millis(100))
        );
        let mut lagging = p.clone();
        let wall = t0 + Duration::from_secs(1);
        lagging.limit_lag(Duration::from_secs(2), wall, Duration::from_secs(1));
        assert_eq!(
            lagging.sim_target(wall),
            Some(Duration::from_secs(3)),
            "10 s of credit cut to 1 s"
        );
        lagging.limit_lag(Duration::from_secs(3), wall, Duration::from_secs(1));
        assert_eq!(
            lagging.sim_target(wall),
            Some(Duration::from_secs(3)),
            "within the limit: unchanged"
        );
        let fast = Pacer::new(SpeedFactor::AsFastAsPossible, Duration::from_millis(4), t0);
        assert_eq!(fast.sim_target(t0), None);
        assert_eq!(fast.wall_due(Duration::from_secs(5)), None);
    }
}
