//! The vehicle as one rigid body: its state in PX4's frames and a step of Newton-Euler integration.
//!
//! Frames: the world is local NED about the home (x North, y East, z Down, metres; z = 0 is the height at
//! which the vehicle rests on the ground); the body is FRD (x forward, y right, z down) with its origin at
//! the centre of mass.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// Where the body is and how it moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyState {
    /// Position of the centre of mass, local NED, metres (z down: -10 is 10 m above the ground).
    pub position_ned_m: Vector3<f64>,
    /// Velocity of the centre of mass, local NED, m/s.
    pub velocity_ned_m_s: Vector3<f64>,
    /// Attitude: the rotation taking body FRD vectors into NED (PX4's `q`: yaw clockwise from North seen
    /// from above, pitch nose up, roll right wing down, all positive).
    pub attitude: UnitQuaternion<f64>,
    /// Angular velocity of the body relative to NED, in body FRD, rad/s (positive = right-handed about
    /// each FRD axis: roll right, pitch up, yaw clockwise from above).
    pub rates_frd_rad_s: Vector3<f64>,
}

impl BodyState {
    /// At rest at a NED position, level, nose at `yaw_rad` (clockwise from North).
    pub fn at_rest(position_ned_m: Vector3<f64>, yaw_rad: f64) -> Self {
        Self {
            position_ned_m,
            velocity_ned_m_s: Vector3::zeros(),
            attitude: UnitQuaternion::from_euler_angles(0.0, 0.0, yaw_rad),
            rates_frd_rad_s: Vector3::zeros(),
        }
    }

    /// A body FRD vector expressed in NED.
    pub fn body_to_ned(&self, v_frd: &Vector3<f64>) -> Vector3<f64> {
        self.attitude * v_frd
    }

    /// A NED vector expressed in body FRD.
    pub fn ned_to_body(&self, v_ned: &Vector3<f64>) -> Vector3<f64> {
        self.attitude.inverse() * v_ned
    }
}

/// Mass properties.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProperties {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Inertia about the centre of mass in body FRD axes, kg m^2.
    pub inertia_frd_kg_m2: Matrix3<f64>,
}

/// The external force and moment on the body, gravity excluded.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force in NED, newtons.
    pub force_ned_n: Vector3<f64>,
    /// Moment about the centre of mass in body FRD, newton metres.
    pub moment_frd_n_m: Vector3<f64>,
}

/// Advances `s` by `dt_s` under `w` and gravity `g_m_s2` (NED +z), semi-implicit Euler: velocities first,
/// then positions with the new velocities (stable for the stiff ground contact), the attitude through the
/// exponential map of the body rate.
pub fn integrate(s: &mut BodyState, m: &MassProperties, w: &Wrench, g_m_s2: f64, dt_s: f64) {
    let accel = w.force_ned_n / m.mass_kg + Vector3::new(0.0, 0.0, g_m_s2);
    s.velocity_ned_m_s += accel * dt_s;
    s.position_ned_m += s.velocity_ned_m_s * dt_s;
    let i = m.inertia_frd_kg_m2;
    let omega = s.rates_frd_rad_s;
    let gyroscopic = omega.cross(&(i * omega));
    let inv = i.try_inverse().unwrap_or_else(Matrix3::identity);
    s.rates_frd_rad_s += inv * (w.moment_frd_n_m - gyroscopic) * dt_s;
    // The body rate rotates the body frame: q <- q * exp(omega dt).
    s.attitude *= UnitQuaternion::from_scaled_axis(s.rates_frd_rad_s * dt_s);
    s.attitude.renormalize();
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    fn iris_like() -> MassProperties {
        MassProperties {
            mass_kg: 1.5,
            inertia_frd_kg_m2: Matrix3::from_diagonal(&Vector3::new(0.029125, 0.029125, 0.055225)),
        }
    }

    #[test]
    fn free_fall_follows_half_g_t_squared() {
        let mut s = BodyState::at_rest(Vector3::new(0.0, 0.0, -100.0), 0.0);
        let dt = 0.001;
        for _ in 0..2000 {
            integrate(&mut s, &iris_like(), &Wrench::default(), 9.8068, dt);
        }
        // z(2 s) = -100 + g t^2 / 2 = -80.3864; semi-implicit Euler adds g dt t / 2 = 0.0098.
        assert!(
            close(s.position_ned_m.z, -100.0 + 0.5 * 9.8068 * 4.0, 0.011),
            "{}",
            s.position_ned_m.z
        );
        assert!(close(s.velocity_ned_m_s.z, 9.8068 * 2.0, 1e-9));
    }

    #[test]
    fn a_yaw_moment_turns_the_nose_clockwise() {
        // tau = I alpha: 0.055225 N m for 1 s gives 1 rad/s about body z (down) = clockwise seen from above.
        let mut s = BodyState::at_rest(Vector3::zeros(), 0.0);
        let w = Wrench {
            force_ned_n: Vector3::new(0.0, 0.0, -1.5 * 9.8068),
            moment_frd_n_m: Vector3::new(0.0, 0.0, 0.055225),
        };
        for _ in 0..1000 {
            integrate(&mut s, &iris_like(), &w, 9.8068, 0.001);
        }
        assert!(close(s.rates_frd_rad_s.z, 1.0, 1e-9));
        let (_, _, yaw) = s.attitude.euler_angles();
        assert!(close(yaw, 0.5, 2e-3), "{yaw}");
    }

    #[test]
    fn body_and_ned_vectors_convert_both_ways() {
        let s = BodyState::at_rest(Vector3::zeros(), std::f64::consts::FRAC_PI_2);
        // Nose East: body forward is NED East.
        let fwd = s.body_to_ned(&Vector3::x());
        assert!(close(fwd.y, 1.0, 1e-12) && close(fwd.x, 0.0, 1e-12));
        let back = s.ned_to_body(&fwd);
        assert!((back - Vector3::x()).norm() < 1e-12);
    }
}
