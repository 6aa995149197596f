//! The Collision Prevention flight's own steps: refuse a vehicle without Collision Prevention, start the
//! pilot and the lidar, and switch to Position mode before arming.
//!
//! A vehicle "ignores OBSTACLE_DISTANCE" when it has no `CP_DIST` parameter (no Collision Prevention library
//! to read the message): it is refused before anything is uploaded. A vehicle without Position mode refuses
//! the mode switch, and the flight ends there, unarmed, quoting the refusal.

use std::time::Duration;

use mavlink::dialects::common::MavCmd;
use tokio::sync::watch;

use super::context::{Session, Stop, stop_for};
use super::report::Status;
use crate::bridge::companion::cp_feed::{self, CpFeed, CpProgress};
use crate::bridge::companion::offboard;
use crate::bridge::px4_version::Release;
use crate::lfs::cp_params::CpParams;
use crate::lfs::cp_pilot::{CpPilot, PilotParams};
use crate::lfs::range_sensor::{RangeSensor, SensorScene};

/// PX4 custom main mode POSCTL (Position mode).
pub const PX4_MAIN_POSCTL: u8 = 3;

impl Session<'_> {
    /// The test's Collision Prevention parameters, once the vehicle shows it has Collision Prevention.
    pub async fn check_collision_prevention(&mut self) -> Result<CpParams, Stop> {
        let params = CpParams::from_params(&self.test.params).map_err(|e| {
            Stop::new(
                Status::Rejected,
                format!("the test's Collision Prevention settings: {e}"),
            )
        })?;
        let otherwise = "refusing the flight";
        if self.read_param("CP_DIST", otherwise).await?.is_none() {
            return Err(Stop::new(
                Status::Rejected,
                "the vehicle has no parameter CP_DIST: it has no Collision Prevention and would ignore \
                 OBSTACLE_DISTANCE, so --mode collision-prevention cannot test it",
            ));
        }
        Ok(params)
    }

    /// `MPC_POS_MODE` for this flight when the vehicle's value is one where its release's Collision Prevention
    /// does not act (PX4 v1.14's default 4 ignores every `OBSTACLE_DISTANCE`), with a warning saying so; `None`
    /// when the value is right or the release is unknown (left as it is).
    pub async fn cp_position_mode(&mut self, release: Option<&Release>) -> Result<Option<(String, f64)>, Stop> {
        let Some(release) = release else { return Ok(None) };
        let now = self
            .read_param("MPC_POS_MODE", "flying with its Position mode as it is")
            .await?;
        let Some(change) = position_mode_change(release, now) else {
            return Ok(None);
        };
        let version = self.px4_version.as_ref().map_or_else(String::new, |v| format!(" {v}"));
        self.warnings.push(format!(
            "MPC_POS_MODE set to {change} for this flight: PX4{version}'s Collision Prevention acts only with \
             MPC_POS_MODE {}, and the vehicle had {}",
            list(release.cp_position_modes),
            now.map_or_else(|| "none".into(), |v| format!("{v:.0}"))
        ));
        Ok(Some(("MPC_POS_MODE".into(), f64::from(change))))
    }

    /// Starts the pilot (over the mission's waypoints, in the vehicle's frame) and the lidar.
    pub fn start_cp_feed(&mut self) -> watch::Receiver<CpProgress> {
        let mut pilot = PilotParams::default();
        if let Some(p) = self.test.params.iter().find(|p| p.name == "NAV_ACC_RAD") {
            pilot.acceptance_m = p.value.clamp(1.0, 3.0);
        }
        let goals = offboard::goals(&self.test.mission);
        let goals = match self.frame {
            Some(f) => goals.into_iter().map(|g| f.to_vehicle(g)).collect(),
            None => goals,
        };
        let feed = CpFeed {
            pilot: CpPilot::new(goals, pilot),
            sensor: RangeSensor::default(),
            scene: SensorScene::new(&self.test.obstacles),
            frame: self.frame,
        };
        let (task, rx) = cp_feed::spawn(self.link.clone(), self.target, feed);
        self.tasks.push(task);
        rx
    }

    /// Back to Position mode when a failsafe took the vehicle out of it mid-flight (e.g. a gap in the sticks
    /// on a busy machine), as a pilot would; at most once per vehicle second, each time a warning.
    pub async fn keep_position_mode(&mut self, last_try: &mut Option<Duration>) {
        let now = self.link.clock().now();
        let flying = self.view.armed && self.view.took_off;
        if !flying
            || self.view.px4_mode.0 == PX4_MAIN_POSCTL
            || last_try.is_some_and(|t| now < t + Duration::from_secs(1))
        {
            return;
        }
        *last_try = Some(now);
        let (main, sub) = self.view.px4_mode;
        self.warnings.push(format!(
            "the vehicle left Position mode (to {main}.{sub}); switched back"
        ));
        let mode = [1.0, f32::from(PX4_MAIN_POSCTL), 0.0, 0.0, 0.0, 0.0, 0.0];
        if let Err(e) = self.command(MavCmd::MAV_CMD_DO_SET_MODE, mode).await {
            self.warnings.push(format!("switching back to Position mode: {e}"));
        }
    }

    /// Position mode once the sticks stream (PX4 refuses it without manual control), then arming.
    pub async fn start_position_mode(&mut self, progress: &mut watch::Receiver<CpProgress>) -> Result<(), Stop> {
        let wait = self.link.clock().wall(Duration::from_secs(5));
        if tokio::time::timeout(wait, progress.wait_for(|p| p.streaming))
            .await
            .is_err()
        {
            return Err(Stop::new(
                Status::LinkLost,
                "no position from the vehicle to start the pilot and the lidar from",
            ));
        }
        let mode = [1.0, f32::from(PX4_MAIN_POSCTL), 0.0, 0.0, 0.0, 0.0, 0.0];
        self.command(MavCmd::MAV_CMD_DO_SET_MODE, mode)
            .await
            .map_err(|e| stop_for("switching to Position mode (POSCTL)", e))?;
        super::ready::arm(self).await
    }
}

/// The `MPC_POS_MODE` to set so that `release`'s Collision Prevention acts, given the vehicle's value (`None`
/// when it already does; a vehicle that did not say is set too).
fn position_mode_change(release: &Release, now: Option<f64>) -> Option<u8> {
    let acts = now.is_some_and(|v| release.cp_position_modes.iter().any(|m| f64::from(*m) == v));
    if acts {
        None
    } else {
        release.cp_position_modes.first().copied()
    }
}

fn list(modes: &[u8]) -> String {
    let names: Vec<String> = modes.iter().map(u8::to_string).collect();
    names.join(" or ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::px4_version::RELEASES;

    fn release(minor: u32) -> &'static Release {
        RELEASES.iter().find(|r| r.minor == minor).unwrap()
    }

    #[test]
    fn the_position_mode_is_set_where_the_release_collision_prevention_acts() {
        // v1.14's default (acceleration based) ignores Collision Prevention: smoothed velocity is set.
        assert_eq!(position_mode_change(release(14), Some(4.0)), Some(3));
        assert_eq!(position_mode_change(release(14), Some(0.0)), None);
        assert_eq!(position_mode_change(release(15), Some(3.0)), None);
        // v1.16 acts only in the acceleration-based mode, its default.
        assert_eq!(position_mode_change(release(16), Some(4.0)), None);
        assert_eq!(position_mode_change(release(16), Some(0.0)), Some(4));
        assert_eq!(position_mode_change(release(17), None), Some(4));
        assert_eq!(list(release(14).cp_position_modes), "3 or 0");
    }
}
