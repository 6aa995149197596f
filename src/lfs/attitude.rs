//! Vehicle pitch for the body-fixed depth camera: a multicopter tilts its thrust to accelerate and to balance
//! drag, so the camera (rigidly mounted 0.1 m ahead of the body) looks down while the vehicle speeds up or
//! cruises and up while it brakes. The motion models are kinematic and level; this adds the pitch a vehicle
//! flying their velocity profile would have.
//!
//! Model: the vehicle follows the motion model's velocity `v` with a first-order lag of `time_constant_s`
//! (filtered velocity `v_f`, `v_f' = (v - v_f) / tau`). Its horizontal specific force is the filtered
//! acceleration plus linear drag, `f = v_f' + drag_per_s * v_f` (ENU, m/s^2). Pitch (radians, positive
//! nose-down, about body y as in docs/planner.md §1.1) is `atan(f . forward / g)`, limited to `max_tilt_deg`;
//! the lateral part of `f` would roll the vehicle, which the renderer does not model (the vehicles of both
//! motion models face their direction of travel, so lateral forces are small).
//!
//! The fast renderer needs vertical image columns, so the simulator applies the pitch through the camera's
//! principal point ([`super::camera::Camera::view_pitch_rad`]), not through the pose.
//!
//! **Measured, and off by default** (`SimConfig::tilt = None`): against the 127 recorded flights (MAE /
//! Spearman / precision / recall of "below 1.5 m") the default constants give paper 0.516 / 0.767 / 0.941 /
//! 0.552 (level 0.515 / 0.765 / 0.917 / 0.569), paper with its fitted delay 0.511 / 0.771 / 1.000 / 0.466 (level
//! 0.478 / 0.798 / 1.000 / 0.500), px4 0.589 / 0.724 / 1.000 / 0.310 (level 0.552 / 0.751 / 1.000 / 0.379). With
//! the 64 x 48 camera, where the exact pitched pose is cheap to render in full: level 0.556 / 0.724, exact pitch
//! 0.528 / 0.749, principal-point pitch 0.577 / 0.718, i.e. both within what moving the obstacles by a centimetre
//! does to these numbers (about 0.01 m MAE and 0.005-0.02 Spearman). A slower vehicle (lag 1 s): paper with
//! its delay 0.510 / 0.782 / 1.000 / 0.448 (worse), px4 0.538 / 0.760 / 1.000 / 0.345 and, with the obstacles
//! moved 1 cm, 0.545 / 0.755 (level: 0.552 / 0.751, 0.555 / 0.734 and 0.551 / 0.743 with 1 cm / -2 cm): about
//! 0.01 m and 0.015 better for px4 at lower recall, too little to change the model `generate` screens with. At
//! cruise the pitch is about 1 degree (drag), and the floor only enters the 15 m sensor range at 10 m altitude
//! above about 19 degrees of pitch.

use nalgebra::{Vector2, Vector3};

/// Standard gravity, m/s^2.
pub const G_M_S2: f64 = 9.806_65;

/// Constants of the tilt model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TiltParams {
    /// Lag of the vehicle behind the motion model's velocity, seconds (> 0).
    pub time_constant_s: f64,
    /// Linear drag per unit speed, 1/s (Gazebo's iris: rotor drag about 0.12 1/s).
    pub drag_per_s: f64,
    /// Tilt limit, degrees (PX4 MPC_TILTMAX_AIR 45).
    pub max_tilt_deg: f64,
}

impl Default for TiltParams {
    /// Lag 0.3 s, drag 0.12 1/s (the iris model's rotor drag: 4 rotors x 8.06e-5 N s/m per rad/s x ~550 rad/s
    /// at hover, over 1.5 kg), 45 degrees.
    fn default() -> Self {
        Self {
            time_constant_s: 0.3,
            drag_per_s: 0.12,
            max_tilt_deg: 45.0,
        }
    }
}

/// Pitch (radians, positive nose-down) of a vehicle with ENU yaw `yaw_enu_rad` whose thrust must supply the
/// horizontal specific force `force_enu` (ENU x East, y North, m/s^2): the body-forward component tilts the nose.
pub fn pitch_for_force(force_enu: &Vector2<f64>, yaw_enu_rad: f64, max_tilt_deg: f64) -> f64 {
    let forward = Vector2::new(yaw_enu_rad.cos(), yaw_enu_rad.sin());
    let limit = max_tilt_deg.to_radians().abs();
    (force_enu.dot(&forward) / G_M_S2).atan().clamp(-limit, limit)
}

/// The tilt model's state between ticks.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TiltState {
    /// Filtered velocity, ENU m/s.
    pub filtered_velocity_enu: Vector3<f64>,
    /// Current pitch, radians, positive nose-down.
    pub pitch_rad: f64,
}

impl TiltState {
    /// Advances `dt` seconds towards the motion model's velocity `velocity_enu` (ENU m/s) and returns the new
    /// pitch for ENU yaw `yaw_enu_rad`.
    pub fn update(&mut self, p: &TiltParams, velocity_enu: &Vector3<f64>, yaw_enu_rad: f64, dt: f64) -> f64 {
        let tau = p.time_constant_s.max(1e-3);
        // Exact discretisation of the first-order lag (stable for any dt).
        let k = 1.0 - (-dt / tau).exp();
        let before = self.filtered_velocity_enu;
        self.filtered_velocity_enu += (velocity_enu - before) * k;
        let acc = if dt > 0.0 {
            (self.filtered_velocity_enu - before) / dt
        } else {
            Vector3::zeros()
        };
        let force = acc.xy() + self.filtered_velocity_enu.xy() * p.drag_per_s;
        self.pitch_rad = pitch_for_force(&force, yaw_enu_rad, p.max_tilt_deg);
        self.pitch_rad
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lfs::camera::Camera;
    use crate::lfs::render::CameraPose;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn forward_force_pitches_the_nose_down_and_braking_up() {
        // Facing North (ENU yaw 90 degrees); 1 m/s^2 towards North is forward.
        let north = Vector2::new(0.0, 1.0);
        let p = pitch_for_force(&north, FRAC_PI_2, 45.0);
        assert!((p - (1.0 / G_M_S2).atan()).abs() < 1e-12 && p > 0.0);
        assert!(
            (pitch_for_force(&-north, FRAC_PI_2, 45.0) + p).abs() < 1e-12,
            "braking: nose up"
        );
        // East is lateral for a North-facing vehicle: no pitch.
        assert!(pitch_for_force(&Vector2::new(1.0, 0.0), FRAC_PI_2, 45.0).abs() < 1e-12);
        // The limit holds.
        let hard = pitch_for_force(&(north * 100.0), FRAC_PI_2, 30.0);
        assert!((hard - 30f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn positive_pitch_makes_the_camera_look_down() {
        // The frame conversion end to end: a forward-accelerating vehicle's camera axis points below the horizon
        // by the pitch, along the vehicle's heading.
        let mut s = TiltState::default();
        let p = TiltParams::default();
        let yaw: f64 = 0.3;
        let v = Vector3::new(yaw.cos(), yaw.sin(), 0.0) * 2.0;
        let pitch = s.update(&p, &v, yaw, 0.1);
        assert!(pitch > 0.0);
        let pose = CameraPose {
            position_enu: Vector3::new(0.0, 0.0, 10.0),
            yaw_enu_rad: yaw,
            pitch_rad: pitch,
        };
        let axis = pose.rotation() * Camera::hfs().ray_body(320, 240).normalize();
        let cam = Camera::hfs();
        // Pixel (320, 240) is half a pixel right of and below the centre; compare with the exact centre ray.
        let centre = pose.rotation() * Vector3::x();
        assert!((axis - centre).norm() < 2.0 / cam.focal_px());
        assert!((centre.z + pitch.sin()).abs() < 1e-12, "looks down by the pitch");
        assert!((centre.y.atan2(centre.x) - yaw).abs() < 1e-12, "along the heading");
        // The camera sits ahead of the body and slightly lower when pitched down.
        let c = pose.camera_position(&cam);
        assert!(c.z < 10.0 && (c.xy().norm() - 0.1 * pitch.cos()).abs() < 1e-6);
    }

    #[test]
    fn steady_cruise_pitch_is_the_drag_angle() {
        let mut s = TiltState::default();
        let p = TiltParams::default();
        let v = Vector3::new(0.0, 1.5, 0.0);
        let mut pitch = 0.0;
        for _ in 0..200 {
            pitch = s.update(&p, &v, FRAC_PI_2, 0.1);
        }
        assert!((pitch - (p.drag_per_s * 1.5 / G_M_S2).atan()).abs() < 1e-9, "{pitch}");
        // Stopping pitches the nose up first, then levels out.
        let braking = s.update(&p, &Vector3::zeros(), FRAC_PI_2, 0.1);
        assert!(braking < 0.0);
        for _ in 0..200 {
            pitch = s.update(&p, &Vector3::zeros(), FRAC_PI_2, 0.1);
        }
        assert!(pitch.abs() < 1e-9);
    }
}
