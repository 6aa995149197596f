//! The vehicle against hand-computed physics.

use nalgebra::Vector3;

use super::Vehicle;
use super::iris::COMMAND;

const G: f64 = 9.8068;
const DT: f64 = 0.004;

/// Hover rotor speed by hand: sqrt(m g / (4 k_f)) = sqrt(1.5 * 9.8068 / (4 * 5.84e-6)) = 793.55 rad/s.
fn hover_speed() -> f64 {
    (1.5 * G / (4.0 * 5.84e-6)).sqrt()
}

fn airborne_at(z: f64) -> Vehicle {
    let mut v = Vehicle::iris();
    v.body.position_ned_m.z = z;
    v
}

#[test]
fn hover_speed_and_command_by_hand() {
    assert!((hover_speed() - 793.55).abs() < 0.01, "{}", hover_speed());
    let u = (hover_speed() - 100.0) / 1000.0;
    assert!((u - 0.6935).abs() < 1e-3, "{u}");
    assert!((COMMAND.reference_rad_s(u, true) - hover_speed()).abs() < 1e-9);
}

#[test]
fn hover_command_holds_altitude_for_10_s() {
    let mut v = airborne_at(-10.0);
    let w = hover_speed();
    for r in &mut v.rotors {
        r.speed_rad_s = w;
    }
    for _ in 0..2500 {
        v.step(&[w; 4], &Vector3::zeros(), DT);
    }
    let p = v.body.position_ned_m;
    assert!((p.z + 10.0).abs() < 0.01, "drifted to {p:?}");
    assert!(p.xy().norm() < 1e-6, "the torques cancel: {p:?}");
    assert!(v.body.rates_frd_rad_s.norm() < 1e-9);
    // Hovering, the accelerometer reads the thrust: -g along body z.
    assert!((v.specific_force_frd() - Vector3::new(0.0, 0.0, -G)).norm() < 1e-3);
}

#[test]
fn motors_off_it_falls_as_g_t_squared_over_two() {
    let mut v = airborne_at(-50.0);
    for _ in 0..500 {
        v.step(&[0.0; 4], &Vector3::zeros(), DT);
    }
    // 2 s: 0.5 * 9.8068 * 4 = 19.614 m (1 ms Euler sub-steps add g h t / 2 = 0.0098 m).
    let fallen = v.body.position_ned_m.z + 50.0;
    assert!((fallen - 19.6136).abs() < 0.012, "{fallen}");
    assert!((v.body.velocity_ned_m_s.z - 2.0 * G).abs() < 1e-9);
    // Falling freely the accelerometer reads zero.
    assert!(v.specific_force_frd().norm() < 1e-9);
}

#[test]
fn idle_on_the_ground_it_stands_still() {
    let mut v = Vehicle::iris();
    let idle = COMMAND.reference_rad_s(0.0, true);
    for _ in 0..2500 {
        v.step(&[idle; 4], &Vector3::zeros(), DT);
        assert_eq!(v.body.position_ned_m, Vector3::zeros());
        assert_eq!(v.body.velocity_ned_m_s, Vector3::zeros());
        assert!(v.is_resting());
    }
    assert_eq!(v.body.rates_frd_rad_s, Vector3::zeros());
    assert!((v.specific_force_frd() - Vector3::new(0.0, 0.0, -G)).norm() < 1e-9);
}

#[test]
fn it_takes_off_when_the_thrust_beats_the_weight() {
    let mut v = Vehicle::iris();
    for _ in 0..500 {
        v.step(&[900.0; 4], &Vector3::zeros(), DT);
    }
    // 4 * 5.84e-6 * 900^2 = 18.92 N against 14.71 N: up at about 2.8 m/s^2.
    assert!(v.body.position_ned_m.z < -2.0, "{:?}", v.body.position_ned_m);
    assert!(!v.is_resting());
}

#[test]
fn a_landing_touches_down_and_comes_to_rest_at_zero() {
    let mut v = airborne_at(-2.0);
    // Descend at 0.7 m/s (PX4's landing speed) near hover thrust; on touching, PX4 winds the thrust down
    // to idle (here over 0.4 s).
    v.body.velocity_ned_m_s.z = 0.7;
    let descend = hover_speed() * 0.995;
    let (mut lowest, mut touched, mut rise) = (f64::MIN, None, 0.0f64);
    for k in 0..3000usize {
        let w = match touched {
            None => descend,
            Some(t) => descend + (100.0 - descend) * ((k - t) as f64 / 100.0).min(1.0),
        };
        v.step(&[w; 4], &Vector3::zeros(), DT);
        let z = v.body.position_ned_m.z;
        if touched.is_none() && z > -v.ground.stroke_m {
            touched = Some(k);
        }
        lowest = lowest.max(z);
        if touched.is_some() {
            // How far it came back up from the deepest point so far (z is down).
            rise = rise.max(lowest - z);
        }
    }
    assert!(touched.is_some(), "never touched down");
    assert!(lowest <= 0.0, "sank below the ground: {lowest}");
    assert!(rise < 0.01, "bounced up {rise} m");
    assert_eq!(v.body.position_ned_m.z, 0.0);
    assert_eq!(v.body.velocity_ned_m_s, Vector3::zeros());
    assert!(v.is_resting());
}

#[test]
fn a_touchdown_at_landing_speed_stays_within_the_accelerometer_range() {
    let mut v = airborne_at(-0.5);
    v.body.velocity_ned_m_s.z = 1.0;
    let mut peak: f64 = 0.0;
    for _ in 0..500 {
        v.step(&[hover_speed() * 0.6; 4], &Vector3::zeros(), DT);
        peak = peak.max(v.specific_force_frd().norm());
    }
    assert!(peak < 16.0 * 9.80665, "{peak}");
    assert!(v.is_resting());
}

#[test]
fn wind_pushes_a_hovering_vehicle_downwind() {
    let mut v = airborne_at(-10.0);
    let w = hover_speed();
    for r in &mut v.rotors {
        r.speed_rad_s = w;
    }
    for _ in 0..250 {
        v.step(&[w; 4], &Vector3::new(0.0, 5.0, 0.0), DT);
    }
    // Rotor drag: 4 * 793.55 * 1.75e-4 * 5 m/s = 2.78 N east at first, 1.85 m/s^2.
    assert!(v.body.velocity_ned_m_s.y > 0.5, "{:?}", v.body.velocity_ned_m_s);
}
