//! One rotor as Gazebo Classic's motor model makes it: a first-order rotor speed, thrust quadratic in the
//! speed and fading with the axial airspeed, rotor drag, the reaction (yaw) moment and the rolling moment.
//!
//! Everything is in body FRD about the centre of mass; the rotor axis points up (FRD -z), the way the
//! thrust pushes.

use nalgebra::Vector3;

/// Which way a rotor turns, seen from above (Gazebo's `turningDirection`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spin {
    /// Counter-clockwise from above: its reaction moment yaws the body clockwise (+FRD z).
    Ccw,
    /// Clockwise from above: its reaction moment yaws the body counter-clockwise (-FRD z).
    Cw,
}

impl Spin {
    /// Gazebo's turning direction: +1 counter-clockwise, -1 clockwise.
    pub fn sign(self) -> f64 {
        match self {
            Spin::Ccw => 1.0,
            Spin::Cw => -1.0,
        }
    }
}

/// A rotor's fixed figures (units in the names; SI otherwise).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorParams {
    /// Hub position from the centre of mass, body FRD, metres.
    pub position_frd_m: Vector3<f64>,
    /// Turning direction.
    pub spin: Spin,
    /// Thrust per squared rotor speed k_f, N / (rad/s)^2.
    pub motor_constant: f64,
    /// Reaction moment per newton of thrust k_m, metres.
    pub moment_constant_m: f64,
    /// Time constant of the rotor speed when speeding up, seconds.
    pub time_constant_up_s: f64,
    /// Time constant of the rotor speed when slowing down, seconds.
    pub time_constant_down_s: f64,
    /// Highest rotor speed, rad/s.
    pub max_rot_velocity_rad_s: f64,
    /// Rotor drag per rotor speed and airspeed across the disc, N / (rad/s) / (m/s).
    pub rotor_drag_coefficient: f64,
    /// Rolling moment per rotor speed and airspeed across the disc, N m / (rad/s) / (m/s).
    pub rolling_moment_coefficient: f64,
    /// Axial airspeed at which the thrust has faded to zero, m/s (Gazebo: 25).
    pub max_axial_airspeed_m_s: f64,
}

/// A rotor and its current speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rotor {
    /// Its figures.
    pub params: RotorParams,
    /// Rotor speed, rad/s, never negative.
    pub speed_rad_s: f64,
}

/// Thrust direction of every rotor: body up (FRD -z).
const AXIS_FRD: Vector3<f64> = Vector3::new(0.0, 0.0, -1.0);

impl Rotor {
    /// A stopped rotor.
    pub fn new(params: RotorParams) -> Self {
        Self {
            params,
            speed_rad_s: 0.0,
        }
    }

    /// Moves the rotor speed towards `reference_rad_s` (capped at the highest speed) for `dt_s`: the exact
    /// zero-order-hold step of a first-order lag, stable for any step, with the up or down time constant.
    pub fn spin_towards(&mut self, reference_rad_s: f64, dt_s: f64) {
        let target = reference_rad_s.clamp(0.0, self.params.max_rot_velocity_rad_s);
        let tau = if target > self.speed_rad_s {
            self.params.time_constant_up_s
        } else {
            self.params.time_constant_down_s
        };
        let a = (-dt_s / tau).exp();
        self.speed_rad_s = a * self.speed_rad_s + (1.0 - a) * target;
    }

    /// Thrust at the current speed with the hub moving at `air_velocity_frd_m_s` through the air, newtons.
    pub fn thrust_n(&self, air_velocity_frd_m_s: &Vector3<f64>) -> f64 {
        let p = &self.params;
        let axial = air_velocity_frd_m_s.dot(&AXIS_FRD).abs();
        let fade = (1.0 - axial / p.max_axial_airspeed_m_s).clamp(0.0, 1.0);
        p.motor_constant * self.speed_rad_s * self.speed_rad_s * fade
    }

    /// Force (body FRD, N) and moment about the centre of mass (body FRD, N m) with the hub moving at
    /// `air_velocity_frd_m_s` relative to the air.
    pub fn wrench(&self, air_velocity_frd_m_s: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let p = &self.params;
        let thrust = self.thrust_n(air_velocity_frd_m_s);
        let across = air_velocity_frd_m_s - AXIS_FRD * air_velocity_frd_m_s.dot(&AXIS_FRD);
        let drag = -self.speed_rad_s * p.rotor_drag_coefficient * across;
        let force = AXIS_FRD * thrust + drag;
        let dir = p.spin.sign();
        let reaction = -dir * thrust * p.moment_constant_m * AXIS_FRD;
        let rolling = -self.speed_rad_s * dir * p.rolling_moment_coefficient * across;
        let moment = p.position_frd_m.cross(&force) + reaction + rolling;
        (force, moment)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vehicle::iris;

    fn rotor(i: usize) -> Rotor {
        Rotor::new(iris::rotors()[i])
    }

    #[test]
    fn a_step_up_reaches_63_percent_at_tau_up() {
        let mut r = rotor(0);
        let dt = 0.0001;
        for _ in 0..125 {
            r.spin_towards(800.0, dt);
        }
        // 1 - 1/e of the step after 12.5 ms, whatever the step size (exact discretisation).
        assert!(
            (r.speed_rad_s - 800.0 * (1.0 - (-1.0f64).exp())).abs() < 1e-9,
            "{}",
            r.speed_rad_s
        );
        let mut coarse = rotor(0);
        coarse.spin_towards(800.0, 0.0125);
        assert!((coarse.speed_rad_s - r.speed_rad_s).abs() < 1e-9);
    }

    #[test]
    fn a_step_down_uses_tau_down_and_the_speed_is_capped() {
        let mut r = rotor(1);
        r.speed_rad_s = 800.0;
        r.spin_towards(0.0, 0.025);
        assert!((r.speed_rad_s - 800.0 * (-1.0f64).exp()).abs() < 1e-9);
        for _ in 0..1000 {
            r.spin_towards(5000.0, 0.004);
        }
        assert!((r.speed_rad_s - 1100.0).abs() < 1e-6);
    }

    #[test]
    fn hover_thrust_by_hand() {
        // 5.84e-6 * 794^2 = 3.6817 N per rotor; four lift 1.5 kg at 9.8068 m/s^2 (14.71 N) at 793.5 rad/s.
        let mut r = rotor(0);
        r.speed_rad_s = 794.0;
        assert!((r.thrust_n(&Vector3::zeros()) - 3.681_746_24).abs() < 1e-6);
        // Climbing at 5 m/s (air from above, along -axis): 1 - 5/25 = 0.8 of it.
        let climbing = r.thrust_n(&Vector3::new(0.0, 0.0, -5.0));
        assert!((climbing - 0.8 * 3.681_746_24).abs() < 1e-6);
    }

    #[test]
    fn the_reaction_moment_yaws_against_the_rotor() {
        for (i, want_sign) in [(0, 1.0), (1, 1.0), (2, -1.0), (3, -1.0)] {
            let mut r = rotor(i);
            r.speed_rad_s = 700.0;
            let (_, m) = r.wrench(&Vector3::zeros());
            let yaw = m.z;
            // ccw rotors (0, 1) yaw the body clockwise (+z FRD), by k_m times the thrust.
            let expect = want_sign * 0.06 * r.thrust_n(&Vector3::zeros());
            assert!((yaw - expect).abs() < 1e-12, "rotor {i}: {yaw} vs {expect}");
        }
    }

    #[test]
    fn thrust_on_the_front_right_rotor_pitches_up_and_rolls_left() {
        let mut r = rotor(0);
        r.speed_rad_s = 700.0;
        let (f, m) = r.wrench(&Vector3::zeros());
        assert!(f.z < 0.0);
        // Front (x > 0) lifting pitches the nose up (+y moment); right side (y > 0) lifting rolls left (-x).
        assert!(m.y > 0.0 && m.x < 0.0, "{m:?}");
    }

    #[test]
    fn rotor_drag_opposes_the_airspeed_across_the_disc() {
        let mut r = rotor(2);
        r.speed_rad_s = 800.0;
        let (f, _) = r.wrench(&Vector3::new(2.0, 0.0, 0.0));
        assert!((f.x - (-800.0 * 1.75e-4 * 2.0)).abs() < 1e-12);
    }
}
