//! The magnetometer as Gazebo's `gazebo_magnetometer_plugin` makes it: the Earth's field at the home
//! (World Magnetic Model) turned into the body frame, plus a Gauss-Markov bias and white noise.

use nalgebra::Vector3;

use crate::noise::{GaussMarkov, Gaussian, Stream};

/// The magnetometer's noise figures (the iris sdf's).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagNoise {
    /// White-noise density, gauss/sqrt(Hz).
    pub noise_density: f64,
    /// Bias random walk, gauss/s/sqrt(Hz).
    pub random_walk: f64,
    /// Bias correlation time, s.
    pub bias_tau_s: f64,
}

impl Default for MagNoise {
    fn default() -> Self {
        Self {
            noise_density: 4e-4,
            random_walk: 6.4e-6,
            bias_tau_s: 600.0,
        }
    }
}

/// The magnetometer and its noise state.
#[derive(Debug, Clone)]
pub struct Magnetometer {
    noise: MagNoise,
    field_ned_gauss: Vector3<f64>,
    rng: Gaussian,
    bias: GaussMarkov,
}

impl Magnetometer {
    /// A magnetometer in the field `field_ned_gauss` (local NED, gauss), drawing from `seed`.
    pub fn new(noise: MagNoise, field_ned_gauss: Vector3<f64>, seed: u64) -> Self {
        Self {
            noise,
            field_ned_gauss,
            rng: Gaussian::new(seed, Stream::Mag),
            bias: GaussMarkov::default(),
        }
    }

    /// The reading in body FRD (gauss) for a body whose `ned_to_body` rotation is given, `dt_s` after the
    /// previous reading.
    pub fn sample(&mut self, ned_to_body: &nalgebra::UnitQuaternion<f64>, dt_s: f64) -> Vector3<f64> {
        let n = self.noise;
        self.bias.step(&mut self.rng, n.random_walk, n.bias_tau_s, dt_s);
        let white = self.rng.vector(n.noise_density / dt_s.sqrt());
        ned_to_body * self.field_ned_gauss + self.bias.value + white
    }
}
