//! The sensors against hand-computed values.

use nalgebra::{UnitQuaternion, Vector3};

use super::{SensorConfig, Sensors};
use crate::time::{STEP, SimTime};
use crate::vehicle::Vehicle;
use crate::world::{atmosphere, magnetic};

fn run(sensors: &mut Sensors, v: &Vehicle, steps: u64) -> Vec<super::SensorFrame> {
    (1..=steps)
        .map(|k| sensors.sample(SimTime::from_micros(k * 4000), v, STEP.as_secs_f64()))
        .collect()
}

fn sensors(seed: u64) -> Sensors {
    Sensors::new(SensorConfig::default(), geodesy::SIM_HOME, 9.8068, seed)
}

#[test]
fn at_rest_level_the_accelerometer_reads_minus_g_and_the_gyro_zero() {
    let v = Vehicle::iris();
    let frames = run(&mut sensors(1), &v, 5000);
    let n = frames.len() as f64;
    let accel: Vector3<f64> = frames.iter().map(|f| f.imu.accel_frd_m_s2).sum::<Vector3<f64>>() / n;
    let gyro: Vector3<f64> = frames.iter().map(|f| f.imu.gyro_frd_rad_s).sum::<Vector3<f64>>() / n;
    // The mean of 5000 draws of sigma 6.37e-3 / sqrt(0.004) = 0.1 m/s^2 is within 0.006 (4 sigma).
    assert!((accel - Vector3::new(0.0, 0.0, -9.8068)).norm() < 0.01, "{accel:?}");
    assert!(gyro.norm() < 0.003, "{gyro:?}");
    let sd = (frames.iter().map(|f| f.imu.accel_frd_m_s2.x.powi(2)).sum::<f64>() / n).sqrt();
    assert!((sd - 6.37e-3 / 0.004f64.sqrt()).abs() < 0.01, "accel noise {sd}");
}

#[test]
fn the_barometer_reads_the_isa_at_488_m() {
    let v = Vehicle::iris();
    let frames = run(&mut sensors(2), &v, 2500);
    let baro: Vec<_> = frames.iter().filter_map(|f| f.baro).collect();
    assert_eq!(baro.len(), 501, "50 Hz: at 4 ms, then every 20 ms up to 10 s");
    let mean = baro.iter().map(|b| b.abs_pressure_hpa).sum::<f64>() / baro.len() as f64;
    // By hand: 1013.25 hPa * (284.978 / 288.15)^5.25588 = 955.98 hPa.
    assert!((mean - 955.983).abs() < 0.002, "{mean}");
    assert!(
        baro.windows(2).any(|w| w[0].abs_pressure_hpa != w[1].abs_pressure_hpa),
        "never constant"
    );
    assert!((baro[0].temperature_c - (284.978 - 273.15)).abs() < 1e-9);
    assert!((baro[0].pressure_alt_m - 488.0).abs() < 0.5);
    assert!((atmosphere::isa(488.0).pressure_pa * 0.01 - 955.983).abs() < 0.001);
}

#[test]
fn the_magnetometer_reads_the_model_turned_into_the_body() {
    let mut v = Vehicle::iris();
    // Nose East: the field's north component appears on body -y (left), east on body +x.
    v.body.attitude = UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2);
    let frames = run(&mut sensors(3), &v, 2500);
    let mags: Vec<Vector3<f64>> = frames.iter().filter_map(|f| f.mag_frd_gauss).collect();
    assert!(
        (mags.len() as i64 - 1000).abs() <= 1,
        "100 Hz over 10 s: {}",
        mags.len()
    );
    let mean: Vector3<f64> = mags.iter().sum::<Vector3<f64>>() / mags.len() as f64;
    let f = magnetic::field(47.397742, 8.545594, 488.0, 2026.0).ned_gauss();
    let expect = Vector3::new(f.y, -f.x, f.z);
    assert!((mean - expect).norm() < 0.002, "{mean:?} vs {expect:?}");
}

#[test]
fn different_seeds_give_different_noise() {
    let v = Vehicle::iris();
    let a = run(&mut sensors(4), &v, 10);
    let b = run(&mut sensors(5), &v, 10);
    assert_ne!(a[3].imu, b[3].imu);
    assert_eq!(run(&mut sensors(4), &v, 10), a);
}
