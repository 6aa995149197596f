//! OFFBOARD mode: SET_POSITION_TARGET_LOCAL_NED setpoints and PX4's failsafe when they stop.

use std::time::Duration;

use mavlink::dialects::common::{MavSeverity, PositionTargetTypemask, SET_POSITION_TARGET_LOCAL_NED_DATA};

use crate::dynamics::{Ned, Setpoint};
use crate::modes::FlightMode;
use crate::vehicle::Vehicle;

impl Vehicle {
    pub(crate) fn on_offboard_setpoint(&mut self, s: &SET_POSITION_TARGET_LOCAL_NED_DATA) {
        use PositionTargetTypemask as T;
        let m = s.type_mask;
        let yaw =
            (!m.contains(T::POSITION_TARGET_TYPEMASK_YAW_IGNORE) && s.yaw.is_finite()).then_some(f64::from(s.yaw));
        let pos_used = !m.intersects(
            T::POSITION_TARGET_TYPEMASK_X_IGNORE
                | T::POSITION_TARGET_TYPEMASK_Y_IGNORE
                | T::POSITION_TARGET_TYPEMASK_Z_IGNORE,
        );
        let vel_used = !m.intersects(
            T::POSITION_TARGET_TYPEMASK_VX_IGNORE
                | T::POSITION_TARGET_TYPEMASK_VY_IGNORE
                | T::POSITION_TARGET_TYPEMASK_VZ_IGNORE,
        );
        let sp = if pos_used && s.x.is_finite() && s.y.is_finite() && s.z.is_finite() {
            Setpoint::Position {
                target_ned: Ned::new(s.x.into(), s.y.into(), s.z.into()),
                h_speed_m_s: self.limits.max_h_speed_m_s,
                up_speed_m_s: self.nav_params.up_m_s,
                down_speed_m_s: self.nav_params.down_m_s,
                yaw_rad: yaw,
            }
        } else if vel_used && s.vx.is_finite() && s.vy.is_finite() && s.vz.is_finite() {
            Setpoint::Velocity {
                vel_ned: Ned::new(s.vx.into(), s.vy.into(), s.vz.into()),
                yaw_rad: yaw,
            }
        } else {
            return;
        };
        self.offboard = Some((sp, self.now));
    }

    pub(crate) fn offboard_failsafe(&mut self) {
        if self.nav.mode() != FlightMode::Offboard {
            return;
        }
        let timeout = Duration::from_secs_f64(self.params.f64("COM_OF_LOSS_T").clamp(0.0, 60.0));
        let stale = self.offboard.is_none_or(|(_, t)| self.now.saturating_sub(t) > timeout);
        if stale {
            self.offboard = None;
            self.failsafe = true;
            let (mode, name) = match self.params.f64("COM_OBL_RC_ACT") as i32 {
                3 => (FlightMode::Rtl, "Return"),
                4 => (FlightMode::Land, "Land"),
                _ => (FlightMode::Loiter, "Hold"),
            };
            self.text(
                MavSeverity::MAV_SEVERITY_CRITICAL,
                &format!("Failsafe: no offboard setpoints, {name} activated"),
            );
            let alt = self.nav_params.takeoff_alt_m;
            self.set_mode(mode, alt);
        }
    }
}
