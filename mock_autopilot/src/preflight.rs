//! PX4 v1.14's readiness before arming, as far as a client can see it: the estimator settles a few seconds
//! (vehicle time) after boot, until then arming is refused with commander's "Preflight Fail" text, GPS has
//! no fix and there is no home; SYS_STATUS carries the pre-arm bit for the current mode; and the navigator's
//! feasibility check (MIS_DIST_1WP) runs when a mission arrives or home becomes valid.

use std::time::Duration;

use geodesy::distance_m;
use mavlink::dialects::common::{MavCmd, MavSeverity};

use crate::modes::FlightMode;
use crate::vehicle::Vehicle;

/// Vehicle time after boot until the estimator has converged (GPS fix, home, arming checks pass): PX4 SITL
/// (SIH) refuses arming for a few seconds after boot with "Preflight Fail: horizontal velocity unstable".
/// Vehicle time, so a mock at 100x settles in 50 ms of wall time.
pub const DEFAULT_ESTIMATOR_SETTLE: Duration = Duration::from_secs(5);

/// Commander's text while the estimator's horizontal velocity innovations are too large (PX4 v1.14
/// src/modules/commander/HealthAndArmingChecks/checks/estimatorCheck.cpp:148).
pub const VELOCITY_UNSTABLE: &str = "Preflight Fail: horizontal velocity unstable";

/// Mission commands whose item carries a position (PX4's `MissionBlock::item_contains_position`, the subset a
/// multicopter mission uses).
fn has_position(cmd: MavCmd) -> bool {
    use MavCmd::*;
    matches!(
        cmd,
        MAV_CMD_NAV_WAYPOINT
            | MAV_CMD_NAV_LOITER_UNLIM
            | MAV_CMD_NAV_LOITER_TURNS
            | MAV_CMD_NAV_LOITER_TIME
            | MAV_CMD_NAV_LAND
            | MAV_CMD_NAV_TAKEOFF
            | MAV_CMD_NAV_LOITER_TO_ALT
    )
}

impl Vehicle {
    /// The estimator has converged: GPS fix, global position and home are valid.
    pub fn estimator_settled(&self) -> bool {
        self.now.saturating_sub(self.boot_at) >= self.estimator_settle
    }

    /// Why arming in `mode` would be refused now, as commander words it (`None` inside: refused without a
    /// STATUSTEXT, as PX4 1.14 reports some checks only as events). `Ok(())`: armable.
    pub(crate) fn arming_check(&self, mode: FlightMode) -> Result<(), Option<&'static str>> {
        if !self.estimator_settled() {
            return Err(Some(VELOCITY_UNSTABLE));
        }
        if self.params.f64("COM_OBS_AVOID") >= 1.0 && !self.avoidance.is_healthy(self.now) {
            return Err(Some("Preflight Fail: Avoidance system not ready"));
        }
        // A missing or infeasible mission only blocks the modes that need it ("No valid mission available" is
        // an event only: PX4 v1.14 HealthAndArmingChecks/checks/modeCheck.cpp:111-123).
        if mode == FlightMode::Mission && self.nav.count() == 0 {
            return Err(None);
        }
        // Position mode requires manual control (PX4 v1.16 ModeUtil/mode_requirements.cpp).
        if mode == FlightMode::Posctl && self.fresh_sticks().is_none() {
            return Err(Some("Preflight Fail: No manual control input"));
        }
        Ok(())
    }

    /// SYS_STATUS MAV_SYS_STATUS_PREARM_CHECK: PX4 v1.14 sets it in `health` only, when the arming checks pass
    /// for the current navigation state (src/modules/mavlink/streams/SYS_STATUS.hpp:146-148).
    pub(crate) fn prearm_ok(&self) -> bool {
        self.arming_check(self.nav.mode()).is_ok()
    }

    /// Runs the navigator's feasibility check on the stored mission once home is valid (PX4 v1.14 mission.cpp
    /// `check_mission_valid`, run on every update and when home first becomes valid). An infeasible mission is
    /// reset to no items (mission.cpp `update_mission`: "reset the mission"), so MISSION_START is denied.
    pub(crate) fn check_feasibility(&mut self) {
        if !self.estimator_settled() {
            self.feasibility_pending = true;
            return;
        }
        self.feasibility_pending = false;
        let max = self.params.f64("MIS_DIST_1WP");
        if max <= 0.0 {
            return;
        }
        let items = &self
            .missions
            .plan(mavlink::dialects::common::MavMissionType::MAV_MISSION_TYPE_MISSION)
            .items;
        // Items without coordinates (0, 0) mean "here" in the mock; PX4 would measure them too.
        let first = items
            .iter()
            .find(|it| has_position(it.command) && (it.x != 0 || it.y != 0));
        let Some(first) = first else { return };
        let (lat, lon) = self.proj.unproject(self.body.pos_ned.x, self.body.pos_ned.y);
        let d = distance_m(lat, lon, f64::from(first.x) * 1e-7, f64::from(first.y) * 1e-7);
        if d >= max {
            // PX4 v1.14 src/modules/navigator/MissionFeasibility/FeasibilityChecker.cpp:628-630.
            let text = format!("First waypoint too far away: {}m, {} max", d as i64, max as i64);
            self.text(MavSeverity::MAV_SEVERITY_CRITICAL, &text);
            self.nav.set_mission(Vec::new());
        }
    }

    /// Once per step: the feasibility check that waited for home.
    pub(crate) fn preflight_step(&mut self) {
        if self.feasibility_pending && self.estimator_settled() {
            self.check_feasibility();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenarios::{GCS, command, mission2, upload};
    use crate::vehicle::VehicleConfig;
    use mavlink::dialects::common::{MavMessage, MavMissionResult, MavMissionType, MavResult, MavSysStatusSensor};

    const DT: Duration = Duration::from_millis(4);

    fn run(v: &mut Vehicle, d: Duration, out: &mut Vec<MavMessage>) {
        let steps = d.as_millis() / DT.as_millis();
        for _ in 0..steps {
            v.step(DT);
            out.extend(v.drain_outbox());
        }
    }

    fn ack(out: &[MavMessage], cmd: MavCmd) -> Option<MavResult> {
        out.iter().rev().find_map(|m| match m {
            MavMessage::COMMAND_ACK(a) if a.command == cmd => Some(a.result),
            _ => None,
        })
    }

    fn texts(out: &[MavMessage]) -> Vec<String> {
        out.iter()
            .filter_map(|m| match m {
                MavMessage::STATUSTEXT(t) => t.text.to_str().ok().map(str::to_string),
                _ => None,
            })
            .collect()
    }

    fn prearm(out: &[MavMessage]) -> Option<bool> {
        out.iter().rev().find_map(|m| match m {
            MavMessage::SYS_STATUS(s) => Some(
                s.onboard_control_sensors_health
                    .contains(MavSysStatusSensor::MAV_SYS_STATUS_PREARM_CHECK),
            ),
            _ => None,
        })
    }

    #[test]
    fn arming_is_refused_until_the_estimator_settles() {
        let mut v = Vehicle::new(VehicleConfig {
            estimator_settle: Duration::from_secs(3),
            ..Default::default()
        });
        let mut out = Vec::new();
        run(&mut v, Duration::from_secs(1), &mut out);
        assert_eq!(prearm(&out), Some(false));
        assert!(
            !out.iter().any(|m| matches!(m, MavMessage::HOME_POSITION(_))),
            "no home yet"
        );
        let gps = out.iter().rev().find_map(|m| match m {
            MavMessage::GPS_RAW_INT(g) => Some(g.fix_type as u8),
            _ => None,
        });
        assert_eq!(gps, Some(1), "GPS_RAW_INT without a fix");
        let arm = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        v.handle(&GCS, &command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm));
        out.extend(v.drain_outbox());
        assert_eq!(
            ack(&out, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM),
            Some(MavResult::MAV_RESULT_TEMPORARILY_REJECTED)
        );
        assert!(
            texts(&out).contains(&VELOCITY_UNSTABLE.to_string()),
            "{:?}",
            texts(&out)
        );
        out.clear();
        run(&mut v, Duration::from_secs(3), &mut out);
        assert_eq!(prearm(&out), Some(true));
        assert!(out.iter().any(|m| matches!(m, MavMessage::HOME_POSITION(_))));
        v.handle(&GCS, &command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm));
        out.extend(v.drain_outbox());
        assert_eq!(
            ack(&out, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM),
            Some(MavResult::MAV_RESULT_ACCEPTED)
        );
    }

    #[test]
    fn a_first_waypoint_beyond_mis_dist_1wp_is_refused_like_px4() {
        let far = geodesy::GeoPoint {
            lat_deg: 0.0,
            lon_deg: 0.0,
            alt_m: 0.0,
        };
        let mut v = Vehicle::new(VehicleConfig {
            home: far,
            estimator_settle: Duration::from_secs(1),
            ..Default::default()
        });
        // Uploaded before home is valid: checked when it becomes valid.
        assert_eq!(
            upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2()),
            Some(MavMissionResult::MAV_MISSION_ACCEPTED)
        );
        let mut out = Vec::new();
        run(&mut v, Duration::from_secs(2), &mut out);
        let t = texts(&out);
        let too_far = t.iter().find(|s| s.starts_with("First waypoint too far away: "));
        assert!(too_far.is_some_and(|s| s.ends_with("m, 900 max")), "{t:?}");
        // Disarmed, the mode change to Mission is allowed; the pre-arm bit then says no.
        let mode = [1.0, 4.0, 4.0, 0.0, 0.0, 0.0, 0.0];
        v.handle(&GCS, &command(MavCmd::MAV_CMD_DO_SET_MODE, mode));
        out.clear();
        run(&mut v, Duration::from_secs(1), &mut out);
        assert_eq!(
            ack(&out, MavCmd::MAV_CMD_DO_SET_MODE),
            Some(MavResult::MAV_RESULT_ACCEPTED)
        );
        assert_eq!(prearm(&out), Some(false));
        v.handle(&GCS, &command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]));
        out.extend(v.drain_outbox());
        assert_eq!(
            ack(&out, MavCmd::MAV_CMD_MISSION_START),
            Some(MavResult::MAV_RESULT_DENIED)
        );
        assert!(texts(&out).contains(&"Mission start denied! No valid mission".to_string()));
        assert!(!v.state().armed);
        let arm = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        v.handle(&GCS, &command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm));
        out.extend(v.drain_outbox());
        assert_eq!(
            ack(&out, MavCmd::MAV_CMD_COMPONENT_ARM_DISARM),
            Some(MavResult::MAV_RESULT_TEMPORARILY_REJECTED),
            "no arming into an invalid mission"
        );
    }
}
