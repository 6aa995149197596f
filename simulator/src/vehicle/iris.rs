//! The Gazebo Classic iris, PX4's reference quadrotor (PX4-SITL_gazebo-classic `models/iris/iris.sdf.jinja`):
//! its mass, inertia, rotors and the command mapping of its `mavlink_interface` channels.
//!
//! The sdf gives rotor positions in Gazebo's body FLU; they are converted here with
//! [`geodesy::frames::flu_to_frd`]. PX4's output `i` drives Gazebo's `motorNumber` `i`: both PX4's airframe
//! (`10016_none_iris` on v1.14/v1.16, `10016_iris` with mixer `quad_w` on v1.12: rotor 0 front right ccw,
//! 1 rear left ccw, 2 front left cw, 3 rear right cw) and the sdf (`rotor_0` at FLU (0.13, -0.22) ccw,
//! ...) put the same rotor at each index.

use geodesy::frames::flu_to_frd;
use nalgebra::{Matrix3, Vector3};

use super::rigid_body::MassProperties;
use super::rotor::{RotorParams, Spin};

/// Gazebo's gravity for the iris world (its IMU plugin's Zurich value), m/s^2.
pub const GRAVITY_M_S2: f64 = 9.8068;

/// The base link's mass and inertia (the rotor, IMU and GPS links, 0.05 kg together, are left out as in
/// the figures PX4's documentation quotes).
pub fn mass() -> MassProperties {
    MassProperties {
        mass_kg: 1.5,
        inertia_frd_kg_m2: Matrix3::from_diagonal(&Vector3::new(0.029125, 0.029125, 0.055225)),
    }
}

/// Rotor hub positions in Gazebo's body FLU (x forward, y left, z up), metres, and turning directions.
const ROTORS_FLU: [([f64; 3], Spin); 4] = [
    ([0.13, -0.22, 0.023], Spin::Ccw),
    ([-0.13, 0.20, 0.023], Spin::Ccw),
    ([0.13, 0.22, 0.023], Spin::Cw),
    ([-0.13, -0.20, 0.023], Spin::Cw),
];

/// The four rotors, index = PX4 output = Gazebo `motorNumber`.
pub fn rotors() -> [RotorParams; 4] {
    ROTORS_FLU.map(|(p, spin)| RotorParams {
        position_frd_m: flu_to_frd(&Vector3::new(p[0], p[1], p[2])),
        spin,
        motor_constant: 5.84e-6,
        moment_constant_m: 0.06,
        time_constant_up_s: 0.0125,
        time_constant_down_s: 0.025,
        max_rot_velocity_rad_s: 1100.0,
        rotor_drag_coefficient: 1.75e-4,
        rolling_moment_coefficient: 1e-6,
        max_axial_airspeed_m_s: 25.0,
    })
}

/// How a HIL_ACTUATOR_CONTROLS value becomes a rotor speed reference (Gazebo's channel `input_scaling`
/// and `zero_position_armed`): `omega_ref = u * scale + armed_offset` rad/s when armed, 0 when disarmed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandMapping {
    /// rad/s per unit of command.
    pub scale_rad_s: f64,
    /// Rotor speed at command 0 while armed, rad/s.
    pub armed_offset_rad_s: f64,
}

/// The iris channels: 1000 rad/s per unit, 100 rad/s idle when armed.
pub const COMMAND: CommandMapping = CommandMapping {
    scale_rad_s: 1000.0,
    armed_offset_rad_s: 100.0,
};

impl CommandMapping {
    /// The rotor speed reference for command `u` (0..1 for a motor).
    pub fn reference_rad_s(&self, u: f64, armed: bool) -> f64 {
        if armed && u.is_finite() {
            u * self.scale_rad_s + self.armed_offset_rad_s
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotors_sit_where_px4s_quad_wide_puts_them() {
        let r = rotors();
        // PX4 (FRD): 0 front right ccw, 1 rear left ccw, 2 front left cw, 3 rear right cw.
        let quadrant = |i: usize| (r[i].position_frd_m.x > 0.0, r[i].position_frd_m.y > 0.0, r[i].spin);
        assert_eq!(quadrant(0), (true, true, Spin::Ccw));
        assert_eq!(quadrant(1), (false, false, Spin::Ccw));
        assert_eq!(quadrant(2), (true, false, Spin::Cw));
        assert_eq!(quadrant(3), (false, true, Spin::Cw));
        assert!(
            (r[0].position_frd_m.z + 0.023).abs() < 1e-12,
            "hubs 23 mm above the centre of mass"
        );
    }

    #[test]
    fn command_mapping_by_hand() {
        assert!((COMMAND.reference_rad_s(0.69, true) - 790.0).abs() < 1e-9);
        assert_eq!(COMMAND.reference_rad_s(0.0, true), 100.0);
        assert_eq!(COMMAND.reference_rad_s(0.69, false), 0.0);
        assert_eq!(COMMAND.reference_rad_s(f64::NAN, true), 0.0);
    }
}
