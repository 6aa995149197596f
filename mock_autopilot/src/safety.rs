//! What stops a flight from outside the plan: the geofence breach and its GF_ACTION, and a crash into the
//! collision world (the vehicle then lies on the ground, disarmed).

use mavlink::dialects::common::MavSeverity;

use crate::dynamics::Ned;
use crate::modes::FlightMode;
use crate::vehicle::Vehicle;

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
            let (mode, what) = match action {
                0 => (None, "no action"),
                1 => (None, "warning only"),
                3 => (Some(FlightMode::Rtl), "Return"),
                5 => (Some(FlightMode::Land), "Land"),
                4 => (None, "Terminate"),
                _ => (Some(FlightMode::Loiter), "Hold"),
            };
            if action != 0 {
                self.text(
                    MavSeverity::MAV_SEVERITY_CRITICAL,
                    &format!("Geofence violated, {what} activated"),
                );
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
