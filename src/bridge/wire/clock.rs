//! Vehicle time: the bridge measures every timeout and rate in the vehicle's seconds, so a simulator running
//! K times faster than real time (the mock's `--speed-factor`, PX4's `PX4_SIM_SPEED_FACTOR`) keeps every
//! protocol timer and stream rate in proportion.

use std::time::{Duration, Instant};

/// Converts between wall time and vehicle time (`vehicle = wall x scale`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleClock {
    start: Instant,
    scale: f64,
}

impl VehicleClock {
    /// A clock starting now; `scale` (> 0, finite) is how much faster the vehicle's time runs. Bad scales
    /// fall back to 1 (callers validate user input first).
    pub fn new(scale: f64) -> Self {
        Self::starting_at(Instant::now(), scale)
    }

    /// A clock starting at `start` (for tests).
    pub fn starting_at(start: Instant, scale: f64) -> Self {
        let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
        Self { start, scale }
    }

    /// The time scale.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The same vehicle time now, running `scale` times wall time from here on (a bad scale keeps the old).
    pub fn rescaled(&self, scale: f64) -> Self {
        if !(scale.is_finite() && scale > 0.0) {
            return *self;
        }
        let wall = Instant::now();
        let vehicle = self.at(wall);
        let start = wall.checked_sub(vehicle.div_f64(scale)).unwrap_or(self.start);
        Self { start, scale }
    }

    /// Vehicle time since the clock started.
    pub fn now(&self) -> Duration {
        self.at(Instant::now())
    }

    /// Vehicle time at wall instant `wall`.
    pub fn at(&self, wall: Instant) -> Duration {
        wall.saturating_duration_since(self.start).mul_f64(self.scale)
    }

    /// The wall duration of a vehicle-time duration.
    pub fn wall(&self, vehicle: Duration) -> Duration {
        vehicle.div_f64(self.scale)
    }

    /// Wall time from now until vehicle time `deadline` (zero if past).
    pub fn wall_until(&self, deadline: Duration) -> Duration {
        self.wall(deadline.saturating_sub(self.now()))
    }
}

/// Seconds as a `Duration`, clamped to 0..=1e9 s so user input never panics.
pub fn secs(s: f64) -> Duration {
    if s.is_finite() {
        Duration::from_secs_f64(s.clamp(0.0, 1e9))
    } else {
        Duration::from_secs(1_000_000_000)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_time() {
        let t0 = Instant::now();
        let c = VehicleClock::starting_at(t0, 20.0);
        assert_eq!(c.at(t0 + Duration::from_millis(100)), Duration::from_secs(2));
        assert_eq!(c.wall(Duration::from_secs(2)), Duration::from_millis(100));
        assert_eq!(VehicleClock::starting_at(t0, f64::NAN).scale(), 1.0);
        assert_eq!(VehicleClock::starting_at(t0, -3.0).scale(), 1.0);
        assert_eq!(c.at(t0 - Duration::from_secs(1)), Duration::ZERO);
        assert_eq!(secs(-1.0), Duration::ZERO);
        assert_eq!(secs(f64::INFINITY), Duration::from_secs(1_000_000_000));
    }

    #[test]
    fn rescaling_keeps_the_vehicle_time() {
        let c = VehicleClock::starting_at(Instant::now() - Duration::from_secs(2), 1.0);
        let r = c.rescaled(10.0);
        assert_eq!(r.scale(), 10.0);
        let (a, b) = (c.now(), r.now());
        assert!(b >= a && b - a < Duration::from_millis(100), "{a:?} -> {b:?}");
        assert_eq!(c.rescaled(f64::NAN), c);
    }
}
