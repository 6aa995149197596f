//! The GPS receiver as Gazebo's `gazebo_gps_plugin` makes it: measured at every step with white noise and
//! a slowly wandering bias, held in a delay line, and reported at 5 Hz as it was 120 ms earlier.
//!
//! Gazebo's figures (random walk 2.0 / 4.0 m/s/sqrt(Hz), noise density 2e-4 / 4e-4 m/sqrt(Hz), velocity
//! noise 0.2 / 0.4 m/s/sqrt(Hz), "correlation time" 60) are applied per 4 ms update as its plugin does:
//! the bias gains `rw sqrt(dt) dt n` and loses 1/60 of itself at every update, which makes it a
//! Gauss-Markov bias of 0.24 s correlation and about 3 mm (xy) / 6 mm (z) spread, the noise 13 um, and the
//! velocity noise 1.3 / 2.5 cm/s: Gazebo's GPS is nearly exact, and so is this one with its defaults.

use std::collections::VecDeque;
use std::time::Duration;

use geodesy::{GeoPoint, LocalProjection};
use nalgebra::Vector3;

use crate::noise::{Gaussian, Stream};
use crate::time::SimTime;

/// The receiver's figures (Gazebo's defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsConfig {
    /// Horizontal / vertical bias random walk, m/s/sqrt(Hz).
    pub random_walk_xy_z: (f64, f64),
    /// Horizontal / vertical position noise density, m/sqrt(Hz).
    pub noise_density_xy_z: (f64, f64),
    /// Horizontal / vertical velocity noise density, m/s/sqrt(Hz).
    pub velocity_noise_density_xy_z: (f64, f64),
    /// The bias loses 1/this of itself at every update.
    pub bias_decay_updates: f64,
    /// Age of a fix when it is reported.
    pub delay: Duration,
    /// Time between reports.
    pub period: Duration,
    /// Reported horizontal / vertical accuracy, metres.
    pub eph_epv_m: (f64, f64),
    /// Reported satellites.
    pub satellites: u8,
}

impl Default for GpsConfig {
    fn default() -> Self {
        Self {
            random_walk_xy_z: (2.0, 4.0),
            noise_density_xy_z: (2e-4, 4e-4),
            velocity_noise_density_xy_z: (0.2, 0.4),
            bias_decay_updates: 60.0,
            delay: Duration::from_millis(120),
            period: Duration::from_millis(200),
            eph_epv_m: (1.0, 1.0),
            satellites: 10,
        }
    }
}

/// One GPS report (a 3D fix).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpsFix {
    /// When the position was measured (the report goes out `delay` later).
    pub measured_at: SimTime,
    /// Position (latitude, longitude in degrees; altitude above mean sea level, metres).
    pub position: GeoPoint,
    /// Velocity, local NED, m/s.
    pub velocity_ned_m_s: Vector3<f64>,
    /// Horizontal accuracy, metres.
    pub eph_m: f64,
    /// Vertical accuracy, metres.
    pub epv_m: f64,
    /// Satellites used.
    pub satellites: u8,
}

/// The receiver, its bias and its delay line.
#[derive(Debug, Clone)]
pub struct Gps {
    config: GpsConfig,
    projection: LocalProjection,
    rng: Gaussian,
    bias_ned_m: Vector3<f64>,
    line: VecDeque<GpsFix>,
    next_report: SimTime,
}

impl Gps {
    /// A receiver about `home` drawing from `seed`; the first report goes out once a fix is `delay` old.
    pub fn new(config: GpsConfig, home: GeoPoint, seed: u64) -> Self {
        Self {
            config,
            projection: LocalProjection::new(home),
            rng: Gaussian::new(seed, Stream::Gps),
            bias_ned_m: Vector3::zeros(),
            line: VecDeque::new(),
            next_report: SimTime::ZERO,
        }
    }

    /// Measures at `t` (a step of `dt_s`) the true position and velocity (local NED); returns the report
    /// due at `t`, if one is.
    pub fn step(
        &mut self,
        t: SimTime,
        position_ned_m: &Vector3<f64>,
        velocity_ned_m_s: &Vector3<f64>,
        dt_s: f64,
    ) -> Option<GpsFix> {
        let fix = self.measure(t, position_ned_m, velocity_ned_m_s, dt_s);
        self.line.push_back(fix);
        while self.line.len() > 1 && self.line[1].measured_at.plus(self.config.delay) <= t {
            self.line.pop_front();
        }
        let oldest = *self.line.front()?;
        if t < self.next_report || oldest.measured_at.plus(self.config.delay) > t {
            return None;
        }
        self.next_report = t.plus(self.config.period);
        Some(oldest)
    }

    fn measure(&mut self, t: SimTime, p: &Vector3<f64>, v: &Vector3<f64>, dt_s: f64) -> GpsFix {
        let c = self.config;
        let axis = |xy_z: (f64, f64)| Vector3::new(xy_z.0, xy_z.0, xy_z.1);
        let sq = dt_s.sqrt();
        let n = Vector3::new(self.rng.sample(), self.rng.sample(), self.rng.sample());
        let white = axis(c.noise_density_xy_z).component_mul(&n) * sq;
        let n = Vector3::new(self.rng.sample(), self.rng.sample(), self.rng.sample());
        let vel_noise = axis(c.velocity_noise_density_xy_z).component_mul(&n) * sq;
        let n = Vector3::new(self.rng.sample(), self.rng.sample(), self.rng.sample());
        let walk = axis(c.random_walk_xy_z).component_mul(&n) * sq;
        self.bias_ned_m += walk * dt_s - self.bias_ned_m / c.bias_decay_updates;
        let measured = p + white + self.bias_ned_m;
        GpsFix {
            measured_at: t,
            position: self.projection.point_at(measured.x, measured.y, measured.z),
            velocity_ned_m_s: v + vel_noise,
            eph_m: c.eph_epv_m.0,
            epv_m: c.eph_epv_m.1,
            satellites: c.satellites,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::time::STEP;

    #[test]
    fn reports_go_out_at_5_hz_120_ms_after_their_measurement() {
        let mut gps = Gps::new(GpsConfig::default(), geodesy::SIM_HOME, 1);
        let mut t = SimTime::ZERO;
        let mut reports = Vec::new();
        for k in 0..500 {
            t = t.plus(STEP);
            // Move north 1 m per step so a report tells when it was measured.
            let p = Vector3::new(k as f64, 0.0, 0.0);
            if let Some(f) = gps.step(t, &p, &Vector3::zeros(), STEP.as_secs_f64()) {
                reports.push((t, f));
            }
        }
        assert!(reports.len() >= 9, "{}", reports.len());
        for w in reports.windows(2) {
            assert_eq!(w[1].0.since(w[0].0), Duration::from_millis(200));
        }
        let proj = LocalProjection::new(geodesy::SIM_HOME);
        for (sent, f) in &reports {
            assert_eq!(sent.since(f.measured_at), Duration::from_millis(120));
            let (north, _) = proj.project(f.position.lat_deg, f.position.lon_deg);
            let k_measured = (f.measured_at.as_micros() / 4000 - 1) as f64;
            assert!((north - k_measured).abs() < 0.05, "{north} vs {k_measured}");
        }
    }

    #[test]
    fn the_bias_stays_within_centimetres() {
        let mut gps = Gps::new(GpsConfig::default(), geodesy::SIM_HOME, 2);
        let mut t = SimTime::ZERO;
        for _ in 0..25_000 {
            t = t.plus(STEP);
            gps.step(t, &Vector3::zeros(), &Vector3::zeros(), STEP.as_secs_f64());
            assert!(gps.bias_ned_m.norm() < 0.05, "{:?}", gps.bias_ned_m);
        }
    }
}
