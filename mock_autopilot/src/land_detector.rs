//! PX4 v1.14's multicopter land detector with the thrust it watches.
//!
//! PX4 declares "landed" in three hysteresis stages (src/modules/land_detector/MulticopterLandDetector.cpp):
//! *ground contact* needs low thrust, a commanded descent and no vertical or horizontal movement; *maybe
//! landed* needs ground contact and minimum thrust; *landed* needs maybe landed. Each stage must hold for
//! LNDMC_TRIG_TIME / 3 (LandDetector.cpp `_set_hysteresis_factor`, factor 1 without a range sensor) and drops at
//! once. So a vehicle held at the ground by a *position* setpoint (hover thrust, no descent commanded) is
//! never detected as landed, however still it sits: exactly what a companion answering the land item with a
//! fixed position does to PX4.
//!
//! The mock has no motors, so the thrust is modelled: in the air hover thrust scaled by the commanded
//! vertical acceleration; resting on the ground PX4's vertical velocity PID pushing against the ground
//! (MPC_Z_VEL_P_ACC, MPC_Z_VEL_I_ACC), so a commanded descent winds the thrust down and a position hold keeps
//! hover thrust. Not modelled: freefall (the mock never falls), rotation (the mock has no body rates), the
//! distance-to-ground check (no range sensor, PX4 then skips it). Frame: local NED (z down), m/s.

use std::time::Duration;

use crate::dynamics::{Body, GRAVITY_M_S2, Ned};
use crate::params::ParamTable;

/// PX4's `systemlib::Hysteresis` as the land detector uses it: a change to true takes effect after the
/// state was requested for `to_true`; a change to false at once (lib/hysteresis/hysteresis.cpp).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hysteresis {
    state: bool,
    requested: bool,
    requested_at: Duration,
}

impl Hysteresis {
    /// Starting in `state`.
    pub fn new(state: bool) -> Self {
        Self {
            state,
            requested: state,
            requested_at: Duration::ZERO,
        }
    }

    /// The current (debounced) state.
    pub fn get(&self) -> bool {
        self.state
    }

    /// Request `wanted` at `now`; becomes true only after `to_true` of continuous requests.
    pub fn update(&mut self, wanted: bool, now: Duration, to_true: Duration) {
        if wanted != self.requested {
            self.requested = wanted;
            self.requested_at = now;
        }
        if self.requested != self.state && (!self.requested || now.saturating_sub(self.requested_at) >= to_true) {
            self.state = self.requested;
        }
    }
}

/// The land detector's parameters (PX4 v1.14 defaults in `params.rs`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandParams {
    /// LNDMC_TRIG_TIME, s: the three stages take a third each.
    pub trig_time_s: f64,
    /// LNDMC_Z_VEL_MAX, m/s: "no vertical movement" below this.
    pub z_vel_max_m_s: f64,
    /// LNDMC_XY_VEL_MAX, m/s: "no horizontal movement" below this.
    pub xy_vel_max_m_s: f64,
    /// MPC_THR_HOVER, normalised thrust.
    pub thr_hover: f64,
    /// MPC_THR_MIN, normalised thrust.
    pub thr_min: f64,
    /// MPC_Z_VEL_P_ACC, (m/s²)/(m/s).
    pub z_vel_p: f64,
    /// MPC_Z_VEL_I_ACC, (m/s²)/m.
    pub z_vel_i: f64,
}

impl LandParams {
    /// From the parameter table (out-of-range values clamped to something that still works).
    pub fn from_params(p: &ParamTable) -> Self {
        let thr_min = p.f64("MPC_THR_MIN").clamp(0.0, 0.5);
        Self {
            trig_time_s: p.f64("LNDMC_TRIG_TIME").clamp(0.1, 10.0),
            z_vel_max_m_s: p.f64("LNDMC_Z_VEL_MAX").max(0.01),
            xy_vel_max_m_s: p.f64("LNDMC_XY_VEL_MAX").max(0.01),
            thr_hover: p.f64("MPC_THR_HOVER").clamp(thr_min + 0.01, 1.0),
            thr_min,
            z_vel_p: p.f64("MPC_Z_VEL_P_ACC").max(0.0),
            z_vel_i: p.f64("MPC_Z_VEL_I_ACC").max(0.0),
        }
    }

    fn stage_time(&self) -> Duration {
        Duration::from_secs_f64(self.trig_time_s / 3.0)
    }

    /// Thrust at `frac` of the way from MPC_THR_MIN to MPC_THR_HOVER.
    fn thrust_at(&self, frac: f64) -> f64 {
        self.thr_min + (self.thr_hover - self.thr_min) * frac
    }
}

/// What the land detector sees in one update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandInputs {
    /// Armed?
    pub armed: bool,
    /// Velocity, local NED m/s.
    pub vel_ned: Ned,
    /// Commanded acceleration, local NED m/s² (the body's; zero while resting on the ground).
    pub acc_ned: Ned,
    /// Resting on the ground (z = 0, not climbing).
    pub on_ground: bool,
    /// The trajectory setpoint's velocity (local NED m/s) from the controller; None when idle.
    pub vel_sp_ned: Option<Ned>,
}

impl LandInputs {
    /// What the detector sees of `body` with trajectory setpoint velocity `vel_sp_ned`.
    pub fn of(armed: bool, body: &Body, vel_sp_ned: Option<Ned>) -> Self {
        Self {
            armed,
            vel_ned: body.vel_ned,
            acc_ned: body.acc_ned,
            on_ground: body.on_ground(),
            vel_sp_ned,
        }
    }
}

/// The land detector's state (landed at boot, as PX4's hysteresis objects start true: LandDetector.h).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandDetector {
    ground_contact: Hysteresis,
    maybe_landed: Hysteresis,
    landed: Hysteresis,
    /// Vertical velocity error integral while pushing against the ground, m/s (PX4's `_vel_int(2)`).
    push_int_m_s: f64,
    thrust: f64,
}

impl Default for LandDetector {
    fn default() -> Self {
        Self {
            ground_contact: Hysteresis::new(true),
            maybe_landed: Hysteresis::new(true),
            landed: Hysteresis::new(true),
            push_int_m_s: 0.0,
            thrust: 0.0,
        }
    }
}

impl LandDetector {
    /// PX4's `vehicle_land_detected.landed`.
    pub fn landed(&self) -> bool {
        self.landed.get()
    }

    /// `vehicle_land_detected.ground_contact`.
    pub fn ground_contact(&self) -> bool {
        self.ground_contact.get()
    }

    /// `vehicle_land_detected.maybe_landed`.
    pub fn maybe_landed(&self) -> bool {
        self.maybe_landed.get()
    }

    /// The modelled collective thrust setpoint (0 = idle, MPC_THR_HOVER = hover) of the last update.
    pub fn thrust(&self) -> f64 {
        self.thrust
    }

    /// Back to landed (reboot, crash to the ground).
    pub fn reset_landed(&mut self) {
        *self = Self::default();
    }

    /// One update at `now` after a physics step of `dt_s` seconds.
    pub fn update(&mut self, now: Duration, dt_s: f64, i: &LandInputs, p: &LandParams) {
        self.thrust = self.model_thrust(i, p, dt_s);
        let stage = p.stage_time();
        let gc = self.ground_contact_now(i, p);
        self.ground_contact.update(gc, now, stage);
        // Maybe landed: minimum thrust (10 % of the range, climb-rate control on in every mode the mock flies)
        // and ground contact (MulticopterLandDetector.cpp l. 260-290).
        let maybe = !i.armed || (self.thrust <= p.thrust_at(0.1) && self.ground_contact.get());
        self.maybe_landed.update(maybe, now, stage);
        let landed = !i.armed || self.maybe_landed.get();
        self.landed.update(landed, now, stage);
    }

    /// `_get_ground_contact_state` (MulticopterLandDetector.cpp l. 159-252).
    fn ground_contact_now(&self, i: &LandInputs, p: &LandParams) -> bool {
        // Wider vertical threshold once landed (l. 171-175).
        let z_max = p.z_vel_max_m_s * if self.landed.get() { 2.5 } else { 1.0 };
        let vertical_movement = i.vel_ned.z.abs() >= z_max;
        let horizontal_movement = i.vel_ned.xy().norm() > p.xy_vel_max_m_s;
        // Low thrust: 60 % of the range, as PX4's hover thrust estimate (MPC_USE_HTE 1) is valid in flight
        // (l. 216-219).
        let low_thrust = self.thrust <= p.thrust_at(0.6);
        // A descent must be commanded until maybe landed (l. 222-236): the trajectory setpoint goes down at
        // least 1.1 LNDMC_Z_VEL_MAX. Idle (motors off) pushes into the ground as well.
        let in_descend = i.vel_sp_ned.is_none_or(|v| v.z >= 1.1 * p.z_vel_max_m_s);
        let descent_ok = in_descend || self.maybe_landed.get() || self.landed.get();
        !i.armed || (low_thrust && descent_ok && !vertical_movement && !horizontal_movement)
    }

    /// The thrust mc_pos_control would command (normalised, PositionControl.cpp `_accelerationControl`: thrust
    /// = hover * (g - a_z) / g, limited to [MPC_THR_MIN, 1]).
    fn model_thrust(&mut self, i: &LandInputs, p: &LandParams, dt_s: f64) -> f64 {
        let Some(vel_sp) = i.vel_sp_ned.filter(|_| i.armed) else {
            // Disarmed, or idle: no thrust (FlightTaskAuto.cpp l. 125-130).
            self.push_int_m_s = 0.0;
            return 0.0;
        };
        let wants_takeoff = vel_sp.z < -0.3; // FlightTaskAuto.cpp l. 192 `_want_takeoff`
        if self.ground_contact.get() && !wants_takeoff {
            // "flying_but_ground_contact" or not taken off: zero thrust, integrator reset
            // (MulticopterPositionControl.cpp l. 474-495).
            self.push_int_m_s = 0.0;
            return 0.0;
        }
        let acc_z = if i.on_ground {
            // The ground holds the vehicle: the velocity error stays and the integrator winds (it stops at
            // the thrust limit, PositionControl.cpp l. 155-158).
            let err = vel_sp.z - i.vel_ned.z;
            let acc = p.z_vel_p * err + p.z_vel_i * self.push_int_m_s;
            if self.thrust_for(acc, p) > p.thr_min && self.thrust_for(acc, p) < 1.0 {
                self.push_int_m_s += err * dt_s;
            }
            acc
        } else {
            self.push_int_m_s = 0.0;
            i.acc_ned.z
        };
        self.thrust_for(acc_z, p)
    }

    fn thrust_for(&self, acc_z_m_s2: f64, p: &LandParams) -> f64 {
        (p.thr_hover * (GRAVITY_M_S2 - acc_z_m_s2) / GRAVITY_M_S2).clamp(p.thr_min, 1.0)
    }
}

#[cfg(test)]
#[path = "land_detector_tests.rs"]
mod tests;
