//! The IMU as Gazebo's `gazebo_imu_plugin` makes it: the true body rate and specific force plus a
//! Gauss-Markov bias and white noise of a given density, every step.

use nalgebra::Vector3;

use crate::noise::{GaussMarkov, Gaussian, Stream};

/// The IMU's noise figures (the Gazebo defaults the iris uses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuNoise {
    /// Gyroscope white-noise density, rad/s/sqrt(Hz).
    pub gyro_noise_density: f64,
    /// Gyroscope bias random walk, rad/s^2/sqrt(Hz).
    pub gyro_random_walk: f64,
    /// Gyroscope bias correlation time, s.
    pub gyro_bias_tau_s: f64,
    /// Accelerometer white-noise density, m/s^2/sqrt(Hz).
    pub accel_noise_density: f64,
    /// Accelerometer bias random walk, m/s^3/sqrt(Hz).
    pub accel_random_walk: f64,
    /// Accelerometer bias correlation time, s.
    pub accel_bias_tau_s: f64,
}

impl Default for ImuNoise {
    fn default() -> Self {
        Self {
            gyro_noise_density: 8.726_646e-4,
            gyro_random_walk: 0.0,
            gyro_bias_tau_s: 1000.0,
            accel_noise_density: 6.37e-3,
            accel_random_walk: 0.0,
            accel_bias_tau_s: 300.0,
        }
    }
}

/// One IMU reading, body FRD.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSample {
    /// Specific force (acceleration minus gravity), m/s^2: (0, 0, -g) at rest, level.
    pub accel_frd_m_s2: Vector3<f64>,
    /// Angular rate, rad/s.
    pub gyro_frd_rad_s: Vector3<f64>,
}

/// The IMU and its noise state.
#[derive(Debug, Clone)]
pub struct Imu {
    noise: ImuNoise,
    rng: Gaussian,
    gyro_bias: GaussMarkov,
    accel_bias: GaussMarkov,
}

impl Imu {
    /// An IMU drawing from `seed`.
    pub fn new(noise: ImuNoise, seed: u64) -> Self {
        Self {
            noise,
            rng: Gaussian::new(seed, Stream::Imu),
            gyro_bias: GaussMarkov::default(),
            accel_bias: GaussMarkov::default(),
        }
    }

    /// The reading of a step of `dt_s` whose true rate and specific force are given (body FRD).
    pub fn sample(&mut self, rates_frd: &Vector3<f64>, specific_force_frd: &Vector3<f64>, dt_s: f64) -> ImuSample {
        let n = self.noise;
        self.gyro_bias
            .step(&mut self.rng, n.gyro_random_walk, n.gyro_bias_tau_s, dt_s);
        let gyro_noise = self.rng.vector(n.gyro_noise_density / dt_s.sqrt());
        self.accel_bias
            .step(&mut self.rng, n.accel_random_walk, n.accel_bias_tau_s, dt_s);
        let accel_noise = self.rng.vector(n.accel_noise_density / dt_s.sqrt());
        ImuSample {
            accel_frd_m_s2: specific_force_frd + self.accel_bias.value + accel_noise,
            gyro_frd_rad_s: rates_frd + self.gyro_bias.value + gyro_noise,
        }
    }
}
