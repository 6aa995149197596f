//! The sensors PX4 reads over HIL, each with its own rate and its own seeded noise stream: the IMU every
//! step, the magnetometer at 100 Hz, the barometer at 50 Hz, the GPS at 5 Hz 120 ms late.

pub mod baro;
pub mod gps;
pub mod imu;
pub mod mag;

use std::time::Duration;

use geodesy::GeoPoint;
use nalgebra::Vector3;

use crate::time::SimTime;
use crate::vehicle::Vehicle;
use crate::world::magnetic;
use baro::{BaroSample, Barometer};
use gps::{Gps, GpsConfig, GpsFix};
use imu::{Imu, ImuNoise, ImuSample};
use mag::{MagNoise, Magnetometer};

/// Every sensor's figures; the defaults are Gazebo Classic's iris.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorConfig {
    /// IMU noise.
    pub imu: ImuNoise,
    /// Magnetometer noise.
    pub mag: MagNoise,
    /// Time between magnetometer readings (Gazebo: 100 Hz).
    pub mag_period: Duration,
    /// Barometer white noise, Pa.
    pub baro_noise_pa: f64,
    /// Time between barometer readings (Gazebo: 50 Hz).
    pub baro_period: Duration,
    /// GPS receiver.
    pub gps: GpsConfig,
    /// Date of the magnetic field, decimal year (the World Magnetic Model's secular variation).
    pub magnetic_year: f64,
}

impl Default for SensorConfig {
    fn default() -> Self {
        Self {
            imu: ImuNoise::default(),
            mag: MagNoise::default(),
            mag_period: Duration::from_millis(10),
            baro_noise_pa: 1.0,
            baro_period: Duration::from_millis(20),
            gps: GpsConfig::default(),
            magnetic_year: 2026.0,
        }
    }
}

/// What the sensors read at one step; `None` where a sensor had no new reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorFrame {
    /// The step's time (PX4's clock in lockstep).
    pub time: SimTime,
    /// Accelerometer and gyroscope, every step.
    pub imu: ImuSample,
    /// Magnetic field, body FRD, gauss.
    pub mag_frd_gauss: Option<Vector3<f64>>,
    /// Barometer.
    pub baro: Option<BaroSample>,
    /// A GPS report due now (measured `delay` earlier).
    pub gps: Option<GpsFix>,
}

/// All the sensors.
#[derive(Debug, Clone)]
pub struct Sensors {
    config: SensorConfig,
    home: GeoPoint,
    imu: Imu,
    mag: Magnetometer,
    baro: Barometer,
    gps: Gps,
    next_mag: SimTime,
    last_mag: SimTime,
    next_baro: SimTime,
}

impl Sensors {
    /// The sensors of a vehicle whose local NED origin is `home` (altitude above mean sea level), drawing
    /// from `seed`. The magnetic field is the model's at the home (it changes by a few nT per km).
    pub fn new(config: SensorConfig, home: GeoPoint, gravity_m_s2: f64, seed: u64) -> Self {
        let field = magnetic::field(home.lat_deg, home.lon_deg, home.alt_m, config.magnetic_year);
        Self {
            config,
            home,
            imu: Imu::new(config.imu, seed),
            mag: Magnetometer::new(config.mag, field.ned_gauss(), seed),
            baro: Barometer::new(config.baro_noise_pa, gravity_m_s2, seed),
            gps: Gps::new(config.gps, home, seed),
            next_mag: SimTime::ZERO,
            last_mag: SimTime::ZERO,
            next_baro: SimTime::ZERO,
        }
    }

    /// The readings at `t`, the end of a step of `dt_s` the vehicle has just made.
    pub fn sample(&mut self, t: SimTime, vehicle: &Vehicle, dt_s: f64) -> SensorFrame {
        let body = &vehicle.body;
        let imu = self
            .imu
            .sample(&body.rates_frd_rad_s, &vehicle.specific_force_frd(), dt_s);
        let mag_frd_gauss = due(&mut self.next_mag, t, self.config.mag_period).then(|| {
            let since = t.since(self.last_mag).as_secs_f64().max(dt_s);
            self.last_mag = t;
            self.mag.sample(&body.attitude.inverse(), since)
        });
        let altitude = self.home.alt_m - body.position_ned_m.z;
        let baro = due(&mut self.next_baro, t, self.config.baro_period).then(|| self.baro.sample(altitude));
        let gps = self.gps.step(t, &body.position_ned_m, &body.velocity_ned_m_s, dt_s);
        SensorFrame {
            time: t,
            imu,
            mag_frd_gauss,
            baro,
            gps,
        }
    }
}

/// Whether a reading scheduled at `next` is due at `t`; moves `next` on by `period` (keeping the average
/// rate when the period is not a whole number of steps: 10 ms readings at 4 ms steps come 8 or 12 ms apart).
fn due(next: &mut SimTime, t: SimTime, period: Duration) -> bool {
    if t < *next {
        return false;
    }
    *next = next.plus(period);
    if *next <= t {
        *next = t.plus(period);
    }
    true
}

#[cfg(test)]
mod tests;
