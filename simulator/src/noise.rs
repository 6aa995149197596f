//! Seeded random draws: one user seed, one independent ChaCha stream per consumer, so adding a sensor
//! never changes the draws of another and a run repeats bit for bit.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The stream number of each consumer of random draws (fixed: changing one changes old runs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// Accelerometer and gyroscope.
    Imu = 1,
    /// Magnetometer.
    Mag = 2,
    /// Barometer.
    Baro = 3,
    /// GPS receiver.
    Gps = 4,
    /// Wind gusts.
    Wind = 5,
}

/// A generator of standard normal draws on its own stream of the user's seed.
#[derive(Debug, Clone)]
pub struct Gaussian {
    rng: ChaCha8Rng,
    spare: Option<f64>,
}

impl Gaussian {
    /// The generator for `stream` of `seed`.
    pub fn new(seed: u64, stream: Stream) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream as u64);
        Self { rng, spare: None }
    }

    /// One draw of N(0, 1) (Box-Muller: two uniforms give two normals, the second is kept).
    pub fn sample(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        // 1 - u keeps the logarithm finite (u in [0, 1)).
        let u1: f64 = 1.0 - self.rng.random::<f64>();
        let u2: f64 = self.rng.random::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }

    /// A vector of three independent N(0, sigma^2) draws.
    pub fn vector(&mut self, sigma: f64) -> nalgebra::Vector3<f64> {
        nalgebra::Vector3::new(self.sample() * sigma, self.sample() * sigma, self.sample() * sigma)
    }
}

/// A first-order Gauss-Markov bias per axis, discretised exactly (Maybeck): `b <- phi b + sigma_d n` with
/// `phi = exp(-dt / tau)` and the driving noise of a random walk `sigma_rw` (unit / s / sqrt(Hz)).
#[derive(Debug, Clone, Default)]
pub struct GaussMarkov {
    /// The current bias, per axis.
    pub value: nalgebra::Vector3<f64>,
}

impl GaussMarkov {
    /// Advances the bias by `dt` seconds.
    pub fn step(&mut self, g: &mut Gaussian, random_walk: f64, tau_s: f64, dt_s: f64) {
        if random_walk == 0.0 || tau_s <= 0.0 {
            return;
        }
        let phi = (-dt_s / tau_s).exp();
        let sigma_d = (random_walk * random_walk * tau_s / 2.0 * (1.0 - (-2.0 * dt_s / tau_s).exp())).sqrt();
        self.value = self.value * phi + g.vector(sigma_d);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stream_repeats_and_streams_differ() {
        let draw = |seed, s| {
            let mut g = Gaussian::new(seed, s);
            (0..5).map(|_| g.sample()).collect::<Vec<_>>()
        };
        assert_eq!(draw(7, Stream::Imu), draw(7, Stream::Imu));
        assert_ne!(draw(7, Stream::Imu), draw(7, Stream::Mag));
        assert_ne!(draw(7, Stream::Imu), draw(8, Stream::Imu));
    }

    #[test]
    fn draws_are_standard_normal() {
        let mut g = Gaussian::new(1, Stream::Imu);
        let n = 40_000;
        let xs: Vec<f64> = (0..n).map(|_| g.sample()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.02, "{mean}");
        assert!((var - 1.0).abs() < 0.03, "{var}");
    }

    #[test]
    fn a_gauss_markov_bias_settles_at_its_stationary_spread() {
        // Stationary variance of the process is sigma_rw^2 tau / 2.
        let (rw, tau, dt) = (0.1, 2.0, 0.01);
        let mut g = Gaussian::new(3, Stream::Mag);
        let mut b = GaussMarkov::default();
        let mut sum2 = 0.0;
        let n = 200_000;
        for _ in 0..n {
            b.step(&mut g, rw, tau, dt);
            sum2 += b.value.x * b.value.x;
        }
        let expect = rw * rw * tau / 2.0;
        let got = sum2 / n as f64;
        assert!((got / expect - 1.0).abs() < 0.15, "{got} vs {expect}");
    }
}
