//! Multirotor kinematics with PX4's speed, acceleration, jerk and yaw-rate limits.
//!
//! A point mass tracks a position or velocity setpoint; the step is fixed and takes `dt` as a
//! parameter, so runs are repeatable. Frame: local NED (x North, y East, z Down), metres.

use nalgebra::Vector3;

use crate::params::ParamTable;

/// A local NED vector (x North, y East, z Down): metres, m/s or m/s² by context.
pub type Ned = Vector3<f64>;

/// Standard gravity, m/s².
pub const GRAVITY_M_S2: f64 = 9.80665;

/// The model's own constants (not PX4 parameters): how the point mass tracks its setpoint. The defaults are
/// the mock's original model; a caller may fit them to a reference (PX4 SITL, another simulator).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    /// Final-approach gain (1/s): vertical speed = gain × distance near the target.
    pub pos_gain: f64,
    /// Velocity-loop gain (1/s): acceleration = gain × velocity error, within the acceleration and jerk limits.
    pub vel_gain: f64,
    /// Seconds of the current velocity by which the horizontal distance to a position target is shortened
    /// before the braking speed is computed: PX4 measures that distance from its smoothed trajectory setpoint,
    /// which runs ahead of the vehicle while it follows (PositionSmoothing.cpp `_getMaxXYSpeed`). 0: from the
    /// vehicle.
    pub lead_s: f64,
    /// RMS of the seeded horizontal gust acceleration per axis (m/s²; 0: none), the stand-in for a real
    /// vehicle's flight-to-flight scatter ([`crate::gusts`]).
    pub gust_acc_m_s2: f64,
    /// Correlation time of the gusts, s.
    pub gust_tau_s: f64,
}

impl Default for Tuning {
    fn default() -> Self {
        Self {
            pos_gain: 1.5,
            vel_gain: 2.5,
            lead_s: 0.0,
            gust_acc_m_s2: 0.0,
            gust_tau_s: 1.0,
        }
    }
}

impl Tuning {
    /// The constants' names for [`Tuning::set`].
    pub const NAMES: [&'static str; 5] = [
        "MOCK_POS_GAIN",
        "MOCK_VEL_GAIN",
        "MOCK_LEAD_S",
        "MOCK_GUST_ACC",
        "MOCK_GUST_TAU",
    ];

    /// Sets a constant by its name in [`Tuning::NAMES`] (clamped to a workable range); false for other names.
    pub fn set(&mut self, name: &str, value: f64) -> bool {
        match name {
            "MOCK_POS_GAIN" => self.pos_gain = value.clamp(0.05, 20.0),
            "MOCK_VEL_GAIN" => self.vel_gain = value.clamp(0.05, 50.0),
            "MOCK_LEAD_S" => self.lead_s = value.clamp(0.0, 10.0),
            "MOCK_GUST_ACC" => self.gust_acc_m_s2 = value.clamp(0.0, 5.0),
            "MOCK_GUST_TAU" => self.gust_tau_s = value.clamp(0.05, 60.0),
            _ => return false,
        }
        true
    }
}

/// Motion limits from PX4 parameters (all positive).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// MPC_XY_VEL_MAX, m/s.
    pub max_h_speed_m_s: f64,
    /// MPC_ACC_HOR, m/s².
    pub acc_hor_m_s2: f64,
    /// MPC_ACC_UP_MAX, m/s².
    pub acc_up_m_s2: f64,
    /// MPC_ACC_DOWN_MAX, m/s².
    pub acc_down_m_s2: f64,
    /// MPC_JERK_AUTO, m/s³.
    pub jerk_m_s3: f64,
    /// MPC_YAWRAUTO_MAX, rad/s.
    pub yaw_rate_rad_s: f64,
    /// The model's own constants.
    pub tuning: Tuning,
}

impl Limits {
    /// Limits from the parameter table (non-positive values fall back to small positives).
    pub fn from_params(p: &ParamTable) -> Self {
        let pos = |name: &str, min: f64| p.f64(name).max(min);
        Self {
            max_h_speed_m_s: pos("MPC_XY_VEL_MAX", 0.1),
            acc_hor_m_s2: pos("MPC_ACC_HOR", 0.1),
            acc_up_m_s2: pos("MPC_ACC_UP_MAX", 0.1),
            acc_down_m_s2: pos("MPC_ACC_DOWN_MAX", 0.1),
            jerk_m_s3: pos("MPC_JERK_AUTO", 0.1),
            yaw_rate_rad_s: pos("MPC_YAWRAUTO_MAX", 1.0).to_radians(),
            tuning: Tuning::default(),
        }
    }

    /// The same limits with the model constants `tuning`.
    pub fn with_tuning(mut self, tuning: Tuning) -> Self {
        self.tuning = tuning;
        self
    }
}

/// What the controller tracks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Setpoint {
    /// Motors off / stay on the ground.
    Idle,
    /// Fly to `target_ned` with speed caps (m/s, positive).
    Position {
        /// Target, local NED metres.
        target_ned: Ned,
        /// Horizontal speed cap.
        h_speed_m_s: f64,
        /// Climb speed cap.
        up_speed_m_s: f64,
        /// Descent speed cap.
        down_speed_m_s: f64,
        /// Heading to turn to (rad, 0 = North, clockwise), None to keep.
        yaw_rad: Option<f64>,
    },
    /// Hold a horizontal position and track a vertical velocity: PX4's land setpoint, position (x, y, NaN)
    /// with velocity (NaN, NaN, vz) (FlightTaskAuto.cpp `_prepareLandSetpoints`, release/1.14 l. 297-299).
    XyPositionZVelocity {
        /// Horizontal target, local NED metres (x North, y East).
        target_xy_ned: (f64, f64),
        /// Horizontal speed cap, m/s (positive).
        h_speed_m_s: f64,
        /// Vertical velocity, m/s, NED (positive down).
        vel_z_m_s: f64,
        /// Heading to turn to, None to keep.
        yaw_rad: Option<f64>,
    },
    /// Track a velocity (local NED, m/s).
    Velocity {
        /// Velocity, local NED m/s.
        vel_ned: Ned,
        /// Heading to turn to, None to keep.
        yaw_rad: Option<f64>,
    },
}

/// The vehicle's kinematic state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Position, local NED metres (ground at z = 0).
    pub pos_ned: Ned,
    /// Velocity, local NED m/s.
    pub vel_ned: Ned,
    /// Commanded acceleration, local NED m/s² (without gravity).
    pub acc_ned: Ned,
    /// Heading, rad (0 = North, clockwise positive), in (-π, π].
    pub yaw_rad: f64,
    /// Yaw rate, rad/s.
    pub yaw_rate_rad_s: f64,
}

impl Default for Body {
    fn default() -> Self {
        Self {
            pos_ned: Ned::zeros(),
            vel_ned: Ned::zeros(),
            acc_ned: Ned::zeros(),
            yaw_rad: 0.0,
            yaw_rate_rad_s: 0.0,
        }
    }
}

/// Wrap an angle to (-π, π].
pub fn wrap_pi(a: f64) -> f64 {
    let w = (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    if w <= -std::f64::consts::PI {
        w + std::f64::consts::TAU
    } else {
        w
    }
}

fn approach_speed(dist: f64, cap: f64, brake_acc: f64, pos_gain: f64) -> f64 {
    cap.min((2.0 * brake_acc * dist).sqrt()).min(pos_gain * dist)
}

/// The highest speed (m/s) from which a jerk-limited stop still ends within `dist_m` at `final_m_s`, as PX4's
/// trajectory generator limits the horizontal speed towards its target (`computeMaxSpeedFromDistance`: a
/// constant deceleration `acc` that starts after the `2 acc / jerk` ramp from full opposite acceleration).
/// Near the target this is about `(jerk / 2 acc) * dist`: with PX4's defaults (jerk 4, acc 3) a gain of only
/// 0.67 /s, which is why PX4 crawls towards a setpoint that stays a few metres ahead (an avoidance carrot).
pub fn max_speed_from_distance(jerk_m_s3: f64, acc_m_s2: f64, dist_m: f64, final_m_s: f64) -> f64 {
    let b = 4.0 * acc_m_s2 * acc_m_s2 / jerk_m_s3;
    let c = -2.0 * acc_m_s2 * dist_m.max(0.0) - final_m_s * final_m_s;
    (0.5 * (-b + (b * b - 4.0 * c).sqrt())).max(final_m_s)
}

impl Body {
    /// True when resting on the ground (z = 0, not climbing).
    pub fn on_ground(&self) -> bool {
        self.pos_ned.z >= 0.0 && self.vel_ned.z >= 0.0
    }

    /// Roll and pitch (rad) a multirotor needs for the current acceleration.
    pub fn roll_pitch_rad(&self) -> (f64, f64) {
        let (s, c) = self.yaw_rad.sin_cos();
        let fwd = self.acc_ned.x * c + self.acc_ned.y * s;
        let right = -self.acc_ned.x * s + self.acc_ned.y * c;
        let up = GRAVITY_M_S2 - self.acc_ned.z;
        (right.atan2(up), -fwd.atan2(up))
    }

    /// The velocity (local NED, m/s) and heading the controller tracks for `sp` from the current state, as
    /// PX4's trajectory setpoint; None for `Idle` (motors idle, no velocity setpoint).
    pub fn velocity_setpoint(&self, sp: &Setpoint, lim: &Limits) -> Option<(Ned, Option<f64>)> {
        let horizontal = |n: f64, e: f64, cap: f64| {
            let err_h = Ned::new(n - self.pos_ned.x, e - self.pos_ned.y, 0.0);
            let d_h = err_h.norm();
            if d_h > 1e-9 {
                let cap = cap.min(lim.max_h_speed_m_s);
                // Braking distance as PX4 sees it from its trajectory setpoint, `lead_s` of motion ahead.
                let ahead = (self.vel_ned.xy().dot(&err_h.xy()) / d_h).max(0.0) * lim.tuning.lead_s;
                let brake_d = (d_h - ahead).max(0.0);
                err_h * (cap.min(max_speed_from_distance(lim.jerk_m_s3, lim.acc_hor_m_s2, brake_d, 0.0)) / d_h)
            } else {
                Ned::zeros()
            }
        };
        match *sp {
            Setpoint::Idle => None,
            Setpoint::Position {
                target_ned,
                h_speed_m_s,
                up_speed_m_s,
                down_speed_m_s,
                yaw_rad,
            } => {
                let v_h = horizontal(target_ned.x, target_ned.y, h_speed_m_s);
                let err_z = target_ned.z - self.pos_ned.z;
                let v_z = if err_z < 0.0 {
                    -approach_speed(-err_z, up_speed_m_s, 0.5 * lim.acc_down_m_s2, lim.tuning.pos_gain)
                } else {
                    approach_speed(err_z, down_speed_m_s, 0.5 * lim.acc_up_m_s2, lim.tuning.pos_gain)
                };
                Some((Ned::new(v_h.x, v_h.y, v_z), yaw_rad))
            }
            Setpoint::XyPositionZVelocity {
                target_xy_ned: (n, e),
                h_speed_m_s,
                vel_z_m_s,
                yaw_rad,
            } => {
                let v_h = horizontal(n, e, h_speed_m_s);
                Some((Ned::new(v_h.x, v_h.y, vel_z_m_s), yaw_rad))
            }
            Setpoint::Velocity { vel_ned, yaw_rad } => {
                let mut v = vel_ned;
                let h = v.xy().norm();
                if h > lim.max_h_speed_m_s {
                    v.x *= lim.max_h_speed_m_s / h;
                    v.y *= lim.max_h_speed_m_s / h;
                }
                Some((v, yaw_rad))
            }
        }
    }

    /// Advance by `dt_s` seconds towards `sp` within `lim`.
    pub fn step(&mut self, sp: &Setpoint, lim: &Limits, dt_s: f64) {
        self.step_disturbed(sp, lim, dt_s, Ned::zeros());
    }

    /// [`Body::step`] with an external acceleration `disturbance_ned` (local NED m/s², e.g. a gust) acting
    /// on the airframe beside the commanded one; the controller only sees its effect on the velocity.
    pub fn step_disturbed(&mut self, sp: &Setpoint, lim: &Limits, dt_s: f64, disturbance_ned: Ned) {
        let Some((vel_des, yaw_des)) = self.velocity_setpoint(sp, lim) else {
            self.vel_ned = Ned::zeros();
            self.acc_ned = Ned::zeros();
            self.yaw_rate_rad_s = 0.0;
            self.pos_ned.z = 0.0_f64.max(self.pos_ned.z);
            return;
        };
        let mut acc_des = (vel_des - self.vel_ned) * lim.tuning.vel_gain;
        let h = acc_des.xy().norm();
        if h > lim.acc_hor_m_s2 {
            acc_des.x *= lim.acc_hor_m_s2 / h;
            acc_des.y *= lim.acc_hor_m_s2 / h;
        }
        acc_des.z = acc_des.z.clamp(-lim.acc_up_m_s2, lim.acc_down_m_s2);
        let delta = acc_des - self.acc_ned;
        let max_delta = lim.jerk_m_s3 * dt_s;
        let delta_norm = delta.norm();
        self.acc_ned += if delta_norm > max_delta {
            delta * (max_delta / delta_norm)
        } else {
            delta
        };
        self.vel_ned += (self.acc_ned + disturbance_ned) * dt_s;
        self.pos_ned += self.vel_ned * dt_s;
        if self.pos_ned.z >= 0.0 && self.vel_ned.z >= 0.0 {
            // Ground contact: no sliding, no sinking.
            self.pos_ned.z = 0.0;
            self.vel_ned = Ned::zeros();
            self.acc_ned = Ned::zeros();
        }
        self.turn(yaw_des, lim, dt_s);
    }

    fn turn(&mut self, yaw_des: Option<f64>, lim: &Limits, dt_s: f64) {
        let Some(yaw_des) = yaw_des.filter(|y| y.is_finite()) else {
            self.yaw_rate_rad_s = 0.0;
            return;
        };
        let err = wrap_pi(yaw_des - self.yaw_rad);
        let max = lim.yaw_rate_rad_s * dt_s;
        let d = err.clamp(-max, max);
        self.yaw_rad = wrap_pi(self.yaw_rad + d);
        self.yaw_rate_rad_s = d / dt_s;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> Limits {
        Limits::from_params(&ParamTable::default())
    }

    fn goto(target: Ned) -> Setpoint {
        Setpoint::Position {
            target_ned: target,
            h_speed_m_s: 5.0,
            up_speed_m_s: 1.5,
            down_speed_m_s: 1.5,
            yaw_rad: Some(1.0),
        }
    }

    #[test]
    fn climbs_and_flies_within_limits_without_overshoot() {
        let lim = limits();
        let mut b = Body::default();
        let dt = 0.004;
        let sp = goto(Ned::new(0.0, 0.0, -10.0));
        let mut max_up = 0.0f64;
        for _ in 0..5000 {
            b.step(&sp, &lim, dt);
            max_up = max_up.max(-b.vel_ned.z);
        }
        assert!((b.pos_ned.z + 10.0).abs() < 0.05, "z {}", b.pos_ned.z);
        assert!(max_up <= 1.5 + 1e-6);
        let sp = goto(Ned::new(-6.84, 53.97, -10.0));
        let target = Ned::new(-6.84, 53.97, -10.0);
        let mut max_h = 0.0f64;
        let mut max_acc = 0.0f64;
        let mut overshoot = 0.0f64;
        let dir = target.xy().normalize();
        for _ in 0..10_000 {
            b.step(&sp, &lim, dt);
            max_h = max_h.max(b.vel_ned.xy().norm());
            max_acc = max_acc.max(b.acc_ned.xy().norm());
            overshoot = overshoot.max(b.pos_ned.xy().dot(&dir) - target.xy().norm());
        }
        assert!((b.pos_ned - target).norm() < 0.05);
        assert!(max_h <= 5.0 + 1e-6, "speed {max_h}");
        assert!(max_acc <= 3.0 + 1e-6);
        assert!(overshoot < 0.3, "overshoot {overshoot}");
        assert!((b.yaw_rad - 1.0).abs() < 1e-9);
    }

    #[test]
    fn braking_speed_matches_px4s_jerk_limited_rule() {
        // b = 4 a^2 / j = 9, speed = (-b + sqrt(b^2 + 8 a d)) / 2: d = 3 m -> 1.685 m/s, d = 5 m -> 2.589 m/s.
        assert!((max_speed_from_distance(4.0, 3.0, 3.0, 0.0) - 1.6847).abs() < 1e-3);
        assert!((max_speed_from_distance(4.0, 3.0, 5.0, 0.0) - 2.5887).abs() < 1e-3);
        assert_eq!(max_speed_from_distance(4.0, 3.0, 0.0, 0.0), 0.0);
        assert_eq!(max_speed_from_distance(4.0, 3.0, -1.0, 0.0), 0.0);
        // Never below the speed wanted at the target; grows with distance.
        assert!(max_speed_from_distance(4.0, 3.0, 0.1, 2.0) >= 2.0);
        let mut last = 0.0;
        for k in 1..100 {
            let v = max_speed_from_distance(4.0, 3.0, f64::from(k) * 0.2, 0.0);
            assert!(v > last);
            last = v;
        }
    }

    #[test]
    fn ground_stops_descent_and_idle_stays_put() {
        let lim = limits();
        let mut b = Body {
            pos_ned: Ned::new(0.0, 0.0, -2.0),
            ..Default::default()
        };
        for _ in 0..5000 {
            b.step(&goto(Ned::new(0.0, 0.0, 1.0)), &lim, 0.004);
        }
        assert_eq!(b.pos_ned.z, 0.0);
        assert!(b.on_ground());
        b.step(&Setpoint::Idle, &lim, 0.004);
        assert_eq!(b.vel_ned, Ned::zeros());
    }

    #[test]
    fn yaw_rate_is_limited_and_wraps() {
        let lim = limits();
        let mut b = Body {
            yaw_rad: 3.0,
            ..Default::default()
        };
        b.step(
            &Setpoint::Velocity {
                vel_ned: Ned::zeros(),
                yaw_rad: Some(-3.0),
            },
            &lim,
            0.1,
        );
        // Shortest way is through ±π, at most 45°/s × 0.1 s.
        assert!((b.yaw_rate_rad_s - 45f64.to_radians()).abs() < 1e-9);
        assert!(b.yaw_rad > 3.0 || b.yaw_rad < -3.0);
        assert!((wrap_pi(4.0) - (4.0 - std::f64::consts::TAU)).abs() < 1e-12);
    }

    #[test]
    fn tuning_by_name_slows_the_turn_and_the_approach() {
        let mut t = Tuning::default();
        assert!(t.set("MOCK_VEL_GAIN", 1.0) && t.set("MOCK_LEAD_S", 1.0) && !t.set("MPC_XY_P", 1.0));
        assert!(
            t.set("MOCK_POS_GAIN", -3.0) && t.pos_gain > 0.0,
            "clamped to a workable value"
        );
        let (soft, stiff) = (limits().with_tuning(t), limits());
        let moving = Body {
            pos_ned: Ned::new(0.0, 0.0, -10.0),
            vel_ned: Ned::new(2.0, 0.0, 0.0),
            ..Default::default()
        };
        let sp = goto(Ned::new(5.0, 0.0, -10.0));
        let v = |lim: &Limits| moving.velocity_setpoint(&sp, lim).map(|(v, _)| v.x).unwrap_or(0.0);
        assert!(v(&soft) < v(&stiff), "the lead shortens the braking distance");
        // A lower velocity gain follows a sideways setpoint more slowly.
        let side = Setpoint::Velocity {
            vel_ned: Ned::new(0.0, 2.0, 0.0),
            yaw_rad: None,
        };
        let (mut a, mut b) = (moving, moving);
        for _ in 0..500 {
            a.step(&side, &soft, 0.004);
            b.step(&side, &stiff, 0.004);
        }
        assert!(a.vel_ned.y < b.vel_ned.y, "{} vs {}", a.vel_ned.y, b.vel_ned.y);
    }

    #[test]
    fn tilt_follows_acceleration() {
        let b = Body {
            acc_ned: Ned::new(1.0, 0.0, 0.0),
            ..Default::default()
        };
        let (roll, pitch) = b.roll_pitch_rad();
        assert!(roll.abs() < 1e-12 && pitch < 0.0, "nose down to accelerate north");
    }
}
