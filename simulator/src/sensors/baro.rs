//! The barometer as Gazebo's `gazebo_barometer_plugin` makes it: the standard atmosphere at the vehicle's
//! altitude above mean sea level with 1 Pa of white noise, so the reading is never constant (PX4 flags a
//! constant barometer STALE).

use crate::noise::{Gaussian, Stream};
use crate::world::atmosphere::isa;

/// One barometer reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaroSample {
    /// Absolute pressure, hPa.
    pub abs_pressure_hpa: f64,
    /// The altitude the pressure stands for, metres above mean sea level.
    pub pressure_alt_m: f64,
    /// Air temperature, degrees Celsius.
    pub temperature_c: f64,
}

/// The barometer and its noise stream.
#[derive(Debug, Clone)]
pub struct Barometer {
    noise_pa: f64,
    gravity_m_s2: f64,
    rng: Gaussian,
}

impl Barometer {
    /// A barometer with `noise_pa` of white noise (Gazebo: 1 Pa), drawing from `seed`.
    pub fn new(noise_pa: f64, gravity_m_s2: f64, seed: u64) -> Self {
        Self {
            noise_pa,
            gravity_m_s2,
            rng: Gaussian::new(seed, Stream::Baro),
        }
    }

    /// The reading at `altitude_amsl_m`.
    pub fn sample(&mut self, altitude_amsl_m: f64) -> BaroSample {
        let air = isa(altitude_amsl_m);
        let noise = self.rng.sample() * self.noise_pa;
        BaroSample {
            abs_pressure_hpa: (air.pressure_pa + noise) * 0.01,
            // The pressure altitude moves with the noise, as a real sensor's would.
            pressure_alt_m: altitude_amsl_m - noise / (air.density_kg_m3 * self.gravity_m_s2),
            temperature_c: air.temperature_k - 273.15,
        }
    }
}
