//! The ground under the vehicle: a landing gear with a short sprung stroke above a hard stop.
//!
//! The gear touches down `stroke_m` above the rest height (NED z = 0) and pushes with a spring that
//! carries half the weight at full stroke and a strong damper, so a touch-down at PX4's landing speed
//! (0.7 m/s) decelerates over two centimetres at under 5 g instead of in one step (a one-step stop reads as an accelerometer spike beyond PX4's 16 g
//! range). Below that the hard stop holds the vehicle exactly at z = 0: while the forces push it into the
//! ground it rests, level, with zero velocity and zero rates, which is what PX4's land detector sees on a
//! real vehicle. Thrust above half the weight lifts it off the stop into the stroke, smoothly.

use nalgebra::{UnitQuaternion, Vector3};

use super::rigid_body::{BodyState, Wrench};

/// The gear's figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// Spring travel above the hard stop, metres.
    pub stroke_m: f64,
    /// Spring rate, N/m.
    pub stiffness_n_m: f64,
    /// Vertical damping, N / (m/s).
    pub damping_n_s_m: f64,
    /// Horizontal friction per m/s of sliding at full load, N / (m/s).
    pub friction_n_s_m: f64,
    /// Yaw friction per rad/s of turning at full load, N m / (rad/s).
    pub yaw_friction_n_m_s: f64,
}

impl Ground {
    /// A gear for a vehicle of `mass_kg` under `g_m_s2`: 5 cm stroke carrying half the weight at full
    /// compression, damped at 50 N s/m per kg (over-critical: no rebound; 1 m/s stops in 2 cm).
    pub fn for_vehicle(mass_kg: f64, g_m_s2: f64) -> Self {
        let stroke_m = 0.05;
        let stiffness_n_m = 0.5 * mass_kg * g_m_s2 / stroke_m;
        Self {
            stroke_m,
            stiffness_n_m,
            damping_n_s_m: 50.0 * mass_kg,
            friction_n_s_m: 5.0 * mass_kg,
            yaw_friction_n_m_s: 0.5,
        }
    }

    /// The gear's push on the body in its stroke (zero when airborne), with friction against sliding and
    /// turning in proportion to the load; `weight_n` scales the friction.
    pub fn stroke_wrench(&self, s: &BodyState, weight_n: f64) -> Wrench {
        let compression = s.position_ned_m.z + self.stroke_m;
        if compression <= 0.0 {
            return Wrench::default();
        }
        let push = (self.stiffness_n_m * compression + self.damping_n_s_m * s.velocity_ned_m_s.z).max(0.0);
        let load = push / weight_n.max(1e-9);
        let v = s.velocity_ned_m_s;
        let friction = -self.friction_n_s_m * load * Vector3::new(v.x, v.y, 0.0);
        Wrench {
            force_ned_n: Vector3::new(friction.x, friction.y, -push),
            moment_frd_n_m: Vector3::new(0.0, 0.0, -self.yaw_friction_n_m_s * load * s.rates_frd_rad_s.z),
        }
    }

    /// The hard stop: keeps the body at or above z = 0 and, when `force_down_n` (the vertical NED force on
    /// it, gravity and the stroke included) pushes it into the ground, holds it at rest, level, heading kept.
    /// Returns whether it rests.
    pub fn hard_stop(&self, s: &mut BodyState, force_down_n: f64) -> bool {
        if s.position_ned_m.z < 0.0 {
            return false;
        }
        s.position_ned_m.z = 0.0;
        if s.velocity_ned_m_s.z > 0.0 {
            s.velocity_ned_m_s.z = 0.0;
        }
        if force_down_n < 0.0 {
            return false;
        }
        let (_, _, yaw) = s.attitude.euler_angles();
        s.attitude = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
        s.velocity_ned_m_s = Vector3::zeros();
        s.rates_frd_rad_s = Vector3::zeros();
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gear_carries_half_the_weight_at_full_stroke() {
        let g = Ground::for_vehicle(1.5, 9.8068);
        let s = BodyState::at_rest(Vector3::zeros(), 0.0);
        let w = g.stroke_wrench(&s, 1.5 * 9.8068);
        assert!((w.force_ned_n.z + 0.5 * 1.5 * 9.8068).abs() < 1e-9);
        let airborne = BodyState::at_rest(Vector3::new(0.0, 0.0, -0.051), 0.0);
        assert_eq!(g.stroke_wrench(&airborne, 14.7), Wrench::default());
    }

    #[test]
    fn the_hard_stop_rests_the_body_level_keeping_its_heading() {
        let g = Ground::for_vehicle(1.5, 9.8068);
        let mut s = BodyState::at_rest(Vector3::new(1.0, 2.0, 0.004), 0.0);
        s.attitude = UnitQuaternion::from_euler_angles(0.02, -0.01, 1.0);
        s.velocity_ned_m_s = Vector3::new(0.1, 0.0, 0.3);
        assert!(g.hard_stop(&mut s, 5.0));
        assert_eq!(s.position_ned_m, Vector3::new(1.0, 2.0, 0.0));
        assert_eq!(s.velocity_ned_m_s, Vector3::zeros());
        let (r, p, y) = s.attitude.euler_angles();
        assert!(r.abs() < 1e-12 && p.abs() < 1e-12 && (y - 1.0).abs() < 1e-12);
        // Pulled up: not resting, but still not below the ground.
        let mut up = BodyState::at_rest(Vector3::new(0.0, 0.0, 0.001), 0.0);
        assert!(!g.hard_stop(&mut up, -1.0));
        assert_eq!(up.position_ned_m.z, 0.0);
    }
}
