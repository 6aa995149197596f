//! What stops a flight from outside the plan: the geofence breach and its GF_ACTION, and a crash into the
//! collision world (the vehicle then lies on the ground, disarmed).

use mavlink::dialects::common::MavSeverity;

use crate::dynamics::Ned;
use crate::modes::FlightMode;
use crate::vehicle::Vehicle;

/// Commander's text while the vehicle is inside an exclusion fence (PX4 v1.14, any GF_ACTION but 0).
pub const GEOFENCE_VIOLATION: &str = "Preflight Fail: Geofence violation";
/// The failsafe framework's text when the breach's action starts (also for GF_ACTION 1, warning only).
pub const FAILSAFE_ACTIVATED: &str = "Failsafe activated\t";

impl Vehicle {
    pub(crate) fn check_fence(&mut self) {
        if self.fence.is_empty() || !self.armed || self.landed {
            self.fence_breached = false;
            return;
        }
        let p = self.body.pos_ned;
        let breach = self.fence.check(p.x, p.y).is_some();
        if breach && !self.fence_breached {
            let action = self.params.f64("GF_ACTION") as i32;
            let mode = match action {
                0 | 1 | 4 => None,
                3 => Some(FlightMode::Rtl),
                5 => Some(FlightMode::Land),
                _ => Some(FlightMode::Loiter),
            };
            if action != 0 {
                // PX4 v1.14's texts on a breach, whatever the action (seen on SIH with GF_ACTION 1): commander's
                // geofence check, then the failsafe framework, which ends the texts it also sends as events
                // with a tab.
                self.text(MavSeverity::MAV_SEVERITY_CRITICAL, GEOFENCE_VIOLATION);
                self.text(MavSeverity::MAV_SEVERITY_CRITICAL, FAILSAFE_ACTIVATED);
            }
            if action == 4 {
                self.crash_to_ground();
                self.disarm("geofence termination");
            } else if let Some(m) = mode {
                self.failsafe = true;
                let alt = self.nav_params.takeoff_alt_m;
                self.set_mode(m, alt);
            }
        }
        self.fence_breached = breach;
    }

    fn crash_to_ground(&mut self) {
        self.body.pos_ned.z = 0.0;
        self.body.vel_ned = Ned::zeros();
        self.body.acc_ned = Ned::zeros();
        self.landed = true;
        self.landed_since = self.now;
        self.land_detector.reset_landed();
    }

    pub(crate) fn check_collision(&mut self) {
        if self.crashed || !self.armed {
            return;
        }
        let hit = self.collision.as_ref().and_then(|c| c.collision(&self.body.pos_ned));
        if let Some(what) = hit {
            self.crashed = true;
            self.crash_to_ground();
            self.text(MavSeverity::MAV_SEVERITY_EMERGENCY, &format!("Crash detected: {what}"));
            self.disarm("crash");
        }
    }
}
