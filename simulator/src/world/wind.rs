//! Wind: a mean wind plus gusts, each axis a first-order Gauss-Markov process on its own seeded stream.
//! Off (calm) by default.

use nalgebra::Vector3;

use crate::noise::{GaussMarkov, Gaussian, Stream};

/// The wind's figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindConfig {
    /// Mean wind: the air's velocity in local NED, m/s (a wind *from* the West blowing East is (0, +v, 0)).
    pub mean_ned_m_s: Vector3<f64>,
    /// Standard deviation of the gusts per axis, m/s (0: steady wind).
    pub gust_sigma_m_s: f64,
    /// Correlation time of the gusts, seconds.
    pub gust_tau_s: f64,
}

impl Default for WindConfig {
    fn default() -> Self {
        Self {
            mean_ned_m_s: Vector3::zeros(),
            gust_sigma_m_s: 0.0,
            gust_tau_s: 2.0,
        }
    }
}

/// The wind as it evolves.
#[derive(Debug, Clone)]
pub struct Wind {
    config: WindConfig,
    gust: GaussMarkov,
    rng: Gaussian,
}

impl Wind {
    /// Calm or the configured wind, drawn from `seed`.
    pub fn new(config: WindConfig, seed: u64) -> Self {
        Self {
            config,
            gust: GaussMarkov::default(),
            rng: Gaussian::new(seed, Stream::Wind),
        }
    }

    /// The air's velocity now, local NED, m/s.
    pub fn velocity_ned_m_s(&self) -> Vector3<f64> {
        self.config.mean_ned_m_s + self.gust.value
    }

    /// Advances the gusts by `dt_s`.
    pub fn step(&mut self, dt_s: f64) {
        let c = &self.config;
        if c.gust_sigma_m_s > 0.0 && c.gust_tau_s > 0.0 {
            // A random walk of sigma sqrt(2 / tau) keeps the stationary spread at sigma.
            let rw = c.gust_sigma_m_s * (2.0 / c.gust_tau_s).sqrt();
            self.gust.step(&mut self.rng, rw, c.gust_tau_s, dt_s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calm_by_default_and_steady_without_gusts() {
        let mut w = Wind::new(WindConfig::default(), 0);
        w.step(0.004);
        assert_eq!(w.velocity_ned_m_s(), Vector3::zeros());
        let mut steady = Wind::new(
            WindConfig {
                mean_ned_m_s: Vector3::new(0.0, 3.0, 0.0),
                ..WindConfig::default()
            },
            0,
        );
        steady.step(0.004);
        assert_eq!(steady.velocity_ned_m_s(), Vector3::new(0.0, 3.0, 0.0));
    }

    #[test]
    fn gusts_have_the_configured_spread_and_repeat_by_seed() {
        let cfg = WindConfig {
            gust_sigma_m_s: 1.5,
            gust_tau_s: 1.0,
            ..WindConfig::default()
        };
        let mut w = Wind::new(cfg, 4);
        let mut sum2 = 0.0;
        let n = 100_000;
        for _ in 0..n {
            w.step(0.01);
            sum2 += w.velocity_ned_m_s().x.powi(2);
        }
        let sigma = (sum2 / n as f64).sqrt();
        assert!((sigma - 1.5).abs() < 0.25, "{sigma}");
        let mut a = Wind::new(cfg, 9);
        let mut b = Wind::new(cfg, 9);
        a.step(0.1);
        b.step(0.1);
        assert_eq!(a.velocity_ned_m_s(), b.velocity_ned_m_s());
    }
}
