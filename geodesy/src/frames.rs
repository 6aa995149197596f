//! The local frames and their conversions, each function named for its direction so call sites say which
//! frame they hold.
//!
//! - local NED (PX4, the product's tests): x North, y East, z Down, metres; PX4 yaw clockwise from North.
//! - planner ENU (PX4-Avoidance, MAVROS, Gazebo's world): x East, y North, z Up, metres; yaw counter-clockwise
//!   from East.
//! - body FRD (PX4): x forward, y right, z down; body FLU (Gazebo, ROS): x forward, y left, z up.
//! - Aerialist's positions: x North, y East like NED, but z is the height **up**.
//!
//! The position conversions swap x/y and negate z (NED/ENU) or negate y and z (FRD/FLU); each is its own
//! inverse, but both directions are named.

use nalgebra::{RealField, Vector3};

/// Local NED vector (x North, y East, z Down) to ENU (x East, y North, z Up).
pub fn ned_to_enu<T: RealField + Copy>(ned: &Vector3<T>) -> Vector3<T> {
    Vector3::new(ned.y, ned.x, -ned.z)
}

/// ENU vector (x East, y North, z Up) to local NED (x North, y East, z Down).
pub fn enu_to_ned<T: RealField + Copy>(enu: &Vector3<T>) -> Vector3<T> {
    Vector3::new(enu.y, enu.x, -enu.z)
}

/// Aerialist-style position (x North, y East, z = height **up**) to ENU.
pub fn north_east_up_to_enu<T: RealField + Copy>(north: T, east: T, up: T) -> Vector3<T> {
    Vector3::new(east, north, up)
}

/// ENU position to Aerialist-style (north, east, height up).
pub fn enu_to_north_east_up<T: RealField + Copy>(enu: &Vector3<T>) -> (T, T, T) {
    (enu.y, enu.x, enu.z)
}

/// Body FLU vector (Gazebo: x forward, y left, z up) to body FRD (PX4: x forward, y right, z down).
pub fn flu_to_frd<T: RealField + Copy>(flu: &Vector3<T>) -> Vector3<T> {
    Vector3::new(flu.x, -flu.y, -flu.z)
}

/// Body FRD vector (PX4) to body FLU (Gazebo).
pub fn frd_to_flu<T: RealField + Copy>(frd: &Vector3<T>) -> Vector3<T> {
    Vector3::new(frd.x, -frd.y, -frd.z)
}

/// Wraps radians to [-pi, pi).
fn wrap_pi<T: RealField + Copy>(a: T) -> T {
    let two_pi = T::two_pi();
    a - two_pi * (a / two_pi + T::from_f64(0.5).unwrap_or_else(T::one)).floor()
}

/// PX4 yaw (radians, clockwise from North) to ENU yaw (radians, counter-clockwise from East), in [-pi, pi).
/// This is MAVROS's `pi/2 - yaw`.
pub fn yaw_ned_to_enu_rad<T: RealField + Copy>(yaw_ned_rad: T) -> T {
    wrap_pi(T::frac_pi_2() - yaw_ned_rad)
}

/// ENU yaw (radians, counter-clockwise from East) to PX4 yaw (radians, clockwise from North), in [-pi, pi).
pub fn yaw_enu_to_ned_rad<T: RealField + Copy>(yaw_enu_rad: T) -> T {
    wrap_pi(T::frac_pi_2() - yaw_enu_rad)
}

/// PX4 yaw in degrees (clockwise from North) to ENU yaw in radians.
pub fn yaw_ned_deg_to_enu_rad<T: RealField + Copy>(yaw_ned_deg: T) -> T {
    yaw_ned_to_enu_rad(yaw_ned_deg.to_radians_rf())
}

/// Degree-to-radian conversion for any real field.
trait ToRadians {
    fn to_radians_rf(self) -> Self;
}

impl<T: RealField + Copy> ToRadians for T {
    fn to_radians_rf(self) -> Self {
        self * T::pi() / T::from_f64(180.0).unwrap_or_else(T::one)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn ned_enu_axes() {
        let north = Vector3::new(1.0f64, 0.0, 0.0);
        let east = Vector3::new(0.0f64, 1.0, 0.0);
        let down = Vector3::new(0.0f64, 0.0, 1.0);
        assert_eq!(ned_to_enu(&north), Vector3::new(0.0, 1.0, 0.0));
        assert_eq!(ned_to_enu(&east), Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(ned_to_enu(&down), Vector3::new(0.0, 0.0, -1.0));
        assert_eq!(
            enu_to_ned(&Vector3::new(2.0f32, 3.0, 4.0)),
            Vector3::new(3.0, 2.0, -4.0)
        );
    }

    #[test]
    fn flu_frd_axes() {
        // Gazebo's iris rotor 0 sits at (0.13, -0.22, 0.023) FLU: front right, just above the body centre.
        let rotor0 = flu_to_frd(&Vector3::new(0.13f64, -0.22, 0.023));
        assert_eq!(rotor0, Vector3::new(0.13, 0.22, -0.023));
        assert_eq!(frd_to_flu(&rotor0), Vector3::new(0.13, -0.22, 0.023));
        // A yaw rate to the left (counter-clockwise seen from above) is +z in FLU and -z in FRD.
        assert_eq!(
            flu_to_frd(&Vector3::new(0.0f64, 0.0, 1.0)),
            Vector3::new(0.0, 0.0, -1.0)
        );
    }

    #[test]
    fn aerialist_height_up() {
        let enu = north_east_up_to_enu(10.0f64, -5.0, 3.5);
        assert_eq!(enu, Vector3::new(-5.0, 10.0, 3.5));
        assert_eq!(enu_to_north_east_up(&enu), (10.0, -5.0, 3.5));
    }

    #[test]
    fn yaw_known_answers() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
        // Facing North: PX4 yaw 0, ENU yaw +90 deg.
        assert!(close(yaw_ned_to_enu_rad(0.0), FRAC_PI_2));
        // Facing East: PX4 +90 deg, ENU 0.
        assert!(close(yaw_ned_to_enu_rad(FRAC_PI_2), 0.0));
        // Facing West: PX4 -90 deg, ENU 180 deg (wrapped to -pi).
        assert!(close(yaw_ned_to_enu_rad(-FRAC_PI_2), -PI));
        // Facing South: PX4 180, ENU -90.
        assert!(close(yaw_ned_to_enu_rad(PI), -FRAC_PI_2));
        assert!(close(yaw_enu_to_ned_rad(0.0), FRAC_PI_2));
        assert!(close(yaw_ned_deg_to_enu_rad(90.0), 0.0));
    }

    #[test]
    fn yaw_agrees_with_heading_vectors() {
        // A heading in NED (cos, sin) must map to the ENU heading vector of the converted yaw.
        for i in 0..36 {
            let yaw_ned = i as f64 * 10.0f64.to_radians() - PI;
            let fwd_ned = Vector3::new(yaw_ned.cos(), yaw_ned.sin(), 0.0);
            let fwd_enu = ned_to_enu(&fwd_ned);
            let yaw_enu = yaw_ned_to_enu_rad(yaw_ned);
            assert!((fwd_enu - Vector3::new(yaw_enu.cos(), yaw_enu.sin(), 0.0)).norm() < 1e-12);
        }
    }

    proptest! {
        #[test]
        fn position_round_trip(x in -1e4f64..1e4, y in -1e4f64..1e4, z in -1e4f64..1e4) {
            let v = Vector3::new(x, y, z);
            prop_assert_eq!(enu_to_ned(&ned_to_enu(&v)), v);
            prop_assert_eq!(ned_to_enu(&enu_to_ned(&v)), v);
        }

        #[test]
        fn body_round_trip(x in -1e4f64..1e4, y in -1e4f64..1e4, z in -1e4f64..1e4) {
            let v = Vector3::new(x, y, z);
            prop_assert_eq!(frd_to_flu(&flu_to_frd(&v)), v);
            // A right-handed frame stays right-handed: the cross product maps like a vector.
            let w = Vector3::new(z, x, y);
            prop_assert!((flu_to_frd(&v.cross(&w)) - flu_to_frd(&v).cross(&flu_to_frd(&w))).norm() < 1e-6 * (1.0 + v.norm() * w.norm()));
        }

        #[test]
        fn yaw_round_trip(yaw in -3.1f64..3.1) {
            let back = yaw_enu_to_ned_rad(yaw_ned_to_enu_rad(yaw));
            prop_assert!((back - yaw).abs() < 1e-12);
        }
    }
}
