//! Position mode (POSCTL) driven by sticks, as PX4 v1.16 flies it with its default `MPC_POS_MODE` 4
//! (FlightTaskManualAcceleration, StickAccelerationXY, FlightTaskManualAltitude, StickYaw): the horizontal
//! stick commands an acceleration up to `MPC_VEL_MANUAL` against a drag that brakes when the stick is
//! released, jerk-limited by `MPC_JERK_MAX`; centred sticks hold position and altitude; the throttle commands
//! a climb or descent rate; the yaw stick a yaw rate. Collision Prevention shapes the stick acceleration.
//!
//! Frames: local NED (x North, y East, z Down), metres, m/s, m/s²; sticks forward/right in the body frame.

use std::time::Duration;

use crate::collision_prevention::{CollisionPrevention, CpEvent, CpParams, RangeInbox, Xy};
use crate::dynamics::{Body, GRAVITY_M_S2, Ned, wrap_pi};
use crate::params::ParamTable;
use crate::sticks::{Sticks, expo_deadzone};

/// The airframe's linear drag (1/s): PX4's SIH quadrotor has `SIH_KDV` 1 N s/m on `SIH_MASS` 1 kg. The
/// velocity loop's integrator works against it, so PX4 reaches a stick speed over seconds, not at once, and
/// overshoots a stop a little when it brakes.
pub const AIR_DRAG_PER_S: f64 = 1.0;

/// The parameters of stick flight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ManualParams {
    /// MPC_VEL_MANUAL, m/s.
    pub vel_manual: f64,
    /// MPC_ACC_HOR, m/s².
    pub acc_hor: f64,
    /// MPC_JERK_MAX, m/s³.
    pub jerk_max: f64,
    /// MPC_XY_P, 1/s.
    pub xy_p: f64,
    /// MPC_XY_VEL_P_ACC, 1/s.
    pub xy_vel_p_acc: f64,
    /// MPC_XY_VEL_I_ACC, 1/s².
    pub xy_vel_i_acc: f64,
    /// MPC_HOLD_DZ: stick dead zone.
    pub hold_dz: f64,
    /// MPC_XY_MAN_EXPO, MPC_Z_MAN_EXPO, MPC_YAW_EXPO.
    pub expo: (f64, f64, f64),
    /// MPC_MAN_Y_MAX, rad/s.
    pub yaw_rate_max: f64,
    /// MPC_Z_VEL_MAX_UP, MPC_Z_VEL_MAX_DN, m/s.
    pub z_vel: (f64, f64),
    /// MPC_ACC_UP_MAX, MPC_ACC_DOWN_MAX, m/s².
    pub z_acc: (f64, f64),
    /// MPC_Z_P, 1/s.
    pub z_p: f64,
    /// MPC_Z_VEL_P_ACC, 1/s.
    pub z_vel_p_acc: f64,
}

impl ManualParams {
    /// From the parameter table (gains and limits kept positive).
    pub fn from_params(p: &ParamTable) -> Self {
        let pos = |n: &str| p.f64(n).max(0.01);
        Self {
            vel_manual: pos("MPC_VEL_MANUAL"),
            acc_hor: pos("MPC_ACC_HOR"),
            jerk_max: pos("MPC_JERK_MAX"),
            xy_p: pos("MPC_XY_P"),
            xy_vel_p_acc: pos("MPC_XY_VEL_P_ACC"),
            xy_vel_i_acc: p.f64("MPC_XY_VEL_I_ACC").max(0.0),
            hold_dz: p.f64("MPC_HOLD_DZ"),
            expo: (p.f64("MPC_XY_MAN_EXPO"), p.f64("MPC_Z_MAN_EXPO"), p.f64("MPC_YAW_EXPO")),
            yaw_rate_max: pos("MPC_MAN_Y_MAX").to_radians(),
            z_vel: (pos("MPC_Z_VEL_MAX_UP"), pos("MPC_Z_VEL_MAX_DN")),
            z_acc: (pos("MPC_ACC_UP_MAX"), pos("MPC_ACC_DOWN_MAX")),
            z_p: pos("MPC_Z_P"),
            z_vel_p_acc: pos("MPC_Z_VEL_P_ACC"),
        }
    }
}

/// What the mode commands this step: the controller's velocity and feed-forward acceleration, and a yaw rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ManualCommand {
    /// Velocity to track, local NED m/s (position corrections included).
    pub vel_ned: Ned,
    /// Feed-forward acceleration plus the velocity integrator's, local NED m/s².
    pub acc_ned: Ned,
    /// Yaw rate, rad/s (clockwise positive).
    pub yaw_rate: f64,
}

/// The state of one activation of Position mode.
#[derive(Debug, Clone, Default)]
pub struct PositionMode {
    vel_sp: Xy,
    acc_sp: Xy,
    pos_lock: Option<Xy>,
    brake_boost: f64,
    vz_sp: f64,
    alt_lock: Option<f64>,
    last_vel_cmd: Xy,
    vel_int: Xy,
    /// Collision Prevention of this activation.
    pub cp: CollisionPrevention,
}

fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

fn sqrt_linear(v: f64) -> f64 {
    if (0.0..1.0).contains(&v) { v.sqrt() } else { v }
}

impl PositionMode {
    /// Starts from the vehicle's motion, as PX4 hands the last setpoint over on activation.
    pub fn start(body: &Body) -> Self {
        Self {
            vel_sp: body.vel_ned.xy(),
            brake_boost: 1.0,
            last_vel_cmd: body.vel_ned.xy(),
            ..Default::default()
        }
    }

    /// One step of `dt_s` with sticks `s` (centred when lost).
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        s: Sticks,
        body: &Body,
        mp: &ManualParams,
        cp: (&CpParams, &RangeInbox, Duration),
        dt_s: f64,
        events: &mut Vec<CpEvent>,
    ) -> ManualCommand {
        let (xy_vel, mut xy_acc) = self.horizontal(s, body, mp, cp, dt_s, events);
        self.vel_int += (xy_vel - body.vel_ned.xy()) * (mp.xy_vel_i_acc * dt_s);
        xy_acc += self.vel_int;
        let (vz, az) = self.vertical(s, body, mp, dt_s);
        let yaw_rate = expo_deadzone(s.yaw, mp.expo.2, mp.hold_dz) * mp.yaw_rate_max;
        ManualCommand {
            vel_ned: Ned::new(xy_vel.x, xy_vel.y, vz),
            acc_ned: Ned::new(xy_acc.x, xy_acc.y, az),
            yaw_rate,
        }
    }

    fn horizontal(
        &mut self,
        s: Sticks,
        body: &Body,
        mp: &ManualParams,
        (cpp, inbox, now): (&CpParams, &RangeInbox, Duration),
        dt: f64,
        events: &mut Vec<CpEvent>,
    ) -> (Xy, Xy) {
        let shape = |v: f64| expo_deadzone(v, mp.expo.0, mp.hold_dz);
        let mut stick = Xy::new(shape(s.pitch), shape(s.roll));
        if stick.norm() > 1.0 {
            stick /= stick.norm();
        }
        let (sin, cos) = body.yaw_rad.sin_cos();
        let stick_ned = Xy::new(cos * stick.x - sin * stick.y, sin * stick.x + cos * stick.y);
        let acc_scale = 2.0 * mp.acc_hor; // twice: against the drag the mean acceleration is half
        let mut acc = stick_ned * acc_scale;
        if self.cp.active(cpp, now) {
            acc = self
                .cp
                .modify(acc, self.vel_sp, body.yaw_rad, (inbox, now), cpp, events);
        }
        let mut drag = self.drag(
            acc_scale / mp.vel_manual,
            dt,
            stick.norm_squared() < f64::from(f32::EPSILON),
            mp,
        );
        let crossing = acc.norm_squared() < f64::from(f32::EPSILON)
            || sign(self.acc_sp.x) != sign(acc.x)
            || sign(self.acc_sp.y) != sign(acc.y);
        if crossing && self.vel_sp.norm_squared() < drag.norm_squared() * dt * dt {
            drag = Xy::zeros();
            self.vel_sp = Xy::zeros();
        }
        acc -= drag;
        self.acc_sp = self.jerk_limited(acc, mp.jerk_max, dt);
        self.vel_sp += self.acc_sp * dt;
        let moving = self.vel_sp.norm_squared() > f64::from(f32::EPSILON);
        match self.pos_lock {
            None if !moving => self.pos_lock = Some(body.pos_ned.xy()),
            Some(_) if moving => {
                self.pos_lock = None;
                self.vel_sp = self.last_vel_cmd;
            }
            _ => {}
        }
        let vel_cmd = match self.pos_lock {
            Some(lock) => self.vel_sp + (lock - body.pos_ned.xy()) * mp.xy_p,
            None => self.vel_sp,
        };
        self.last_vel_cmd = vel_cmd;
        (vel_cmd, self.acc_sp)
    }

    /// `acc` within MPC_JERK_MAX of the last acceleration, per axis in proportion to the change so both axes
    /// arrive together.
    fn jerk_limited(&self, mut acc: Xy, jerk_max: f64, dt: f64) -> Xy {
        let change = acc - self.acc_sp;
        let dir = if change.norm() > 0.0 {
            change / change.norm()
        } else {
            Xy::zeros()
        };
        for k in 0..2 {
            let max = dir[k].abs() * jerk_max * dt;
            acc[k] = self.acc_sp[k] + change[k].clamp(-max, max);
        }
        acc
    }

    /// The drag that limits the speed to MPC_VEL_MANUAL, boosted (over 0.8 s) while the stick is released so
    /// the vehicle brakes harder, with a square-root rise below 1 m/s so it stops exactly.
    fn drag(&mut self, coefficient: f64, dt: f64, released: bool, mp: &ManualParams) -> Xy {
        let target = if released { mp.vel_manual.sqrt().max(2.0) } else { 1.0 };
        self.brake_boost += dt / (dt + 0.8) * (target - self.brake_boost);
        let v = self.vel_sp;
        let boosted = if v.norm() > 0.0 {
            v / v.norm() * sqrt_linear(v.norm())
        } else {
            Xy::zeros()
        };
        let brake_scale = (self.brake_boost - 1.0).clamp(0.0, 1.0);
        (boosted * brake_scale + v * (1.0 - brake_scale)) * (coefficient * self.brake_boost)
    }

    /// The climb or descent rate from the throttle, or altitude hold when it is centred.
    fn vertical(&mut self, s: Sticks, body: &Body, mp: &ManualParams, dt: f64) -> (f64, f64) {
        let z = expo_deadzone(-s.throttle, mp.expo.1, mp.hold_dz);
        let target = if z > 0.0 { z * mp.z_vel.1 } else { z * mp.z_vel.0 };
        let (up, down) = mp.z_acc;
        let before = self.vz_sp;
        self.vz_sp += (target - self.vz_sp).clamp(-up * dt, down * dt);
        if target == 0.0 && self.vz_sp.abs() < 0.01 {
            self.vz_sp = 0.0;
            self.alt_lock.get_or_insert(body.pos_ned.z);
        } else if target != 0.0 {
            self.alt_lock = None;
        }
        let vz = self.vz_sp + self.alt_lock.map_or(0.0, |lock| (lock - body.pos_ned.z) * mp.z_p);
        (vz, (self.vz_sp - before) / dt)
    }
}

impl Body {
    /// Tracks a stick command for `dt_s` seconds: PX4's velocity controller (P gains `MPC_XY_VEL_P_ACC`,
    /// `MPC_Z_VEL_P_ACC`, with the feed-forward and integrator accelerations, within a 45-degree tilt and the
    /// vertical acceleration limits) against the airframe's drag [`AIR_DRAG_PER_S`], plus an external
    /// acceleration `disturbance` (gusts).
    pub fn track_manual(&mut self, c: &ManualCommand, mp: &ManualParams, dt_s: f64, disturbance: Ned) {
        if self.on_ground() && c.vel_ned.z >= 0.0 {
            // Landed and not asked to climb: the motors idle and nothing moves.
            self.acc_ned = Ned::zeros();
            self.yaw_rate_rad_s = 0.0;
            return;
        }
        let mut acc = c.acc_ned;
        acc.x += (c.vel_ned.x - self.vel_ned.x) * mp.xy_vel_p_acc;
        acc.y += (c.vel_ned.y - self.vel_ned.y) * mp.xy_vel_p_acc;
        acc.z = (c.acc_ned.z + (c.vel_ned.z - self.vel_ned.z) * mp.z_vel_p_acc).clamp(-mp.z_acc.0, mp.z_acc.1);
        let h = acc.xy().norm();
        if h > GRAVITY_M_S2 {
            acc.x *= GRAVITY_M_S2 / h;
            acc.y *= GRAVITY_M_S2 / h;
        }
        self.acc_ned = acc;
        let drag = Ned::new(self.vel_ned.x, self.vel_ned.y, 0.0) * AIR_DRAG_PER_S;
        self.vel_ned += (acc - drag + disturbance) * dt_s;
        self.pos_ned += self.vel_ned * dt_s;
        if self.pos_ned.z >= 0.0 && self.vel_ned.z >= 0.0 {
            self.pos_ned.z = 0.0;
            self.vel_ned = Ned::zeros();
            self.acc_ned = Ned::zeros();
        }
        self.yaw_rate_rad_s = c.yaw_rate;
        self.yaw_rad = wrap_pi(self.yaw_rad + c.yaw_rate * dt_s);
    }
}

#[cfg(test)]
#[path = "position_mode_tests.rs"]
mod tests;
