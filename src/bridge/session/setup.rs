//! Everything before the first command of the flight: the avoidance companion, the case study's parameters,
//! the mission (uploaded and read back), the obstacles as a geofence, the position streams and readiness;
//! and, after the flight, the parameters put back.

use std::time::Duration;

use mavlink::dialects::common::{MavCmd, MavMissionType};

use super::capability::{self, AVOIDANCE_SWITCH};
use super::context::{Session, Stop, stop_for};
use super::flight;
use super::ready;
use super::report::Status;
use crate::bridge::companion::{avoidance, pacing};
use crate::bridge::options::FlyMode;
use crate::bridge::wire::cancel::CancelToken;
use crate::bridge::wire::exchange::{ProtocolError, RetryPolicy};
use crate::bridge::wire::mission_download::MissionDownload;
use crate::bridge::wire::mission_upload::MissionUpload;
use crate::bridge::wire::params::ParamSet;
use crate::bridge::wire::plan_items::{fence_items, first_difference, mission_items};
use crate::model::LocalProjection;

/// GF_ACTION = 1: the fence only warns, so it never steers the test.
const GF_WARNING_ONLY: f64 = 1.0;
/// PX4 rates heartbeats every half of its 2.5 s heartbeat timeout, and none in its first 2.5 s (v1.14
/// `MavlinkReceiver::CheckHeartbeats`): after this much vehicle time the companion counts as present.
const COMPANION_SEEN: Duration = Duration::from_millis(3000);
/// LOCAL_POSITION_NED rate requested, Hz: at least 30, so the recorded path (and the closest approach found
/// on it) is dense whatever the vehicle streams by default.
pub const POSITION_RATE_HZ: f64 = 50.0;
/// TRAJECTORY_REPRESENTATION_WAYPOINTS rate requested when the companion runs on simulated time, Hz.
pub const REQUEST_RATE_HZ: f64 = 50.0;
/// TRAJECTORY_REPRESENTATION_WAYPOINTS' message id.
const TRAJECTORY_REPRESENTATION_WAYPOINTS_ID: u16 = 332;

impl Session<'_> {
    /// Everything before the first command of the flight.
    pub async fn prepare(&mut self) -> Result<(), Stop> {
        let cp = match self.opts.mode {
            FlyMode::CollisionPrevention => Some(self.check_collision_prevention().await?),
            _ => None,
        };
        self.companion_seen().await?;
        self.set_params(cp).await?;
        if self.opts.mode != FlyMode::Mission {
            // PX4-Avoidance plans with the vehicle's cruise speed (its waypoint speed and line-pull distance);
            // read after the case's parameters are set, since they may change it.
            let otherwise = "the planner keeps PX4's default 5 m/s";
            self.mpc_xy_cruise_m_s = self
                .read_param("MPC_XY_CRUISE", otherwise)
                .await?
                .filter(|v| v.is_finite() && *v > 0.0);
        }
        if self.opts.mode == FlyMode::Avoidance {
            let steer = flight::steer_for(self.test, self.opts, self.frame, self.mpc_xy_cruise_m_s);
            let pacing = match (&self.opts.sim_gate, self.opts.lockstep) {
                (Some(gate), _) => pacing::Pacing::SimulatedTime(pacing::SimPaced {
                    gate: gate.clone(),
                    frame: self.frame,
                    test_home: self.test.home,
                    period: avoidance::ANSWER_PERIOD,
                }),
                (None, Some(latency)) => pacing::Pacing::Lockstep { latency },
                (None, None) => pacing::Pacing::FreeRunning,
            };
            let companion = self.companion.clone();
            let answers = pacing::spawn(self.link.clone(), self.target, steer, companion, pacing);
            self.tasks.push(answers);
        }
        self.upload_mission().await?;
        self.upload_fence().await?;
        self.request_streams().await;
        let mut st = ready::ReadyState::default();
        ready::wait_ready(self, &mut st).await
    }

    /// Waits until PX4 has rated the companion's heartbeats ([`COMPANION_SEEN`] after the first), so that
    /// setting COM_OBS_AVOID never finds the avoidance system missing.
    async fn companion_seen(&mut self) -> Result<(), Stop> {
        let Some(from) = self.companion_beat_from else {
            return Ok(());
        };
        let wait = self.link.clock().wall_until(from + COMPANION_SEEN);
        tokio::select! {
            _ = self.cancel.cancelled() => Err(Stop::new(Status::Aborted, "cancelled")),
            _ = tokio::time::sleep(wait) => Ok(()),
        }
    }

    async fn set_params(&mut self, cp: Option<crate::lfs::cp_params::CpParams>) -> Result<(), Stop> {
        let release = self.check_release()?;
        let case: Vec<(String, f64)> = self.test.params.iter().map(|p| (p.name.clone(), p.value)).collect();
        let mut interface = release.map(|r| r.avoidance_interface);
        let position_mode = match cp {
            Some(_) => self.cp_position_mode(release).await?,
            None => None,
        };
        loop {
            let (mut wanted, skipped) = capability::wanted_params(&case, self.opts.mode, interface);
            if let Some(cp) = cp {
                // Collision Prevention's own values replace the case study's, which may name them too.
                let own = cp.to_params();
                wanted.retain(|(n, _)| !own.iter().any(|(o, _)| o == n));
                wanted.extend(own);
                wanted.extend(position_mode.clone());
            }
            if !skipped.is_empty() {
                let version = self.px4_version.as_ref().map(|v| v.text.clone());
                self.warnings
                    .push(capability::skipped_warning(&skipped, version.as_deref()));
            }
            let p = ParamSet::new(self.target, wanted, RetryPolicy::PARAM);
            match self.link.exchange(p, &self.cancel).await {
                Ok(_) => return Ok(()),
                // A vehicle of unknown release that turns out to lack the avoidance interface.
                Err(ProtocolError::UnknownParam { name }) if name == AVOIDANCE_SWITCH && interface.is_none() => {
                    if self.opts.mode == FlyMode::Avoidance {
                        return Err(self.no_avoidance_interface());
                    }
                    interface = Some(false);
                }
                Err(e) => return Err(stop_for("setting the case-study parameters", e)),
            }
        }
    }

    async fn upload_mission(&mut self) -> Result<(), Stop> {
        let items = mission_items(&self.test.mission).map_err(|e| Stop::new(Status::Rejected, e))?;
        let ty = MavMissionType::MAV_MISSION_TYPE_MISSION;
        let up = MissionUpload::new(self.target, ty, items.clone(), RetryPolicy::MISSION);
        self.link
            .exchange(up, &self.cancel)
            .await
            .map_err(|e| stop_for("uploading the mission", e))?;
        self.ready.mission_uploaded_at = Some(self.link.clock().now());
        let down = MissionDownload::new(self.target, ty, RetryPolicy::MISSION);
        let got = self
            .link
            .exchange(down, &self.cancel)
            .await
            .map_err(|e| stop_for("reading the mission back", e))?;
        match first_difference(&items, &got) {
            None => Ok(()),
            Some(d) => Err(stop_for("checking the mission", ProtocolError::MissionMismatch(d))),
        }
    }

    /// The obstacles as exclusion polygons with GF_ACTION warning-only; a refusal is a warning, not a stop.
    /// Without a fence, any stale fence from an earlier test is cleared so it cannot steer this one.
    async fn upload_fence(&mut self) -> Result<(), Stop> {
        let ty = MavMissionType::MAV_MISSION_TYPE_FENCE;
        let wanted = self.opts.fence && !self.test.obstacles.is_empty();
        let items = if wanted {
            fence_items(&self.test.obstacles, &LocalProjection::new(self.test.home))
        } else {
            Vec::new()
        };
        let up = MissionUpload::new(self.target, ty, items, RetryPolicy::MISSION);
        match self.link.exchange(up, &self.cancel).await {
            Ok(_) if wanted => {}
            Ok(_) => return Ok(()),
            Err(ProtocolError::Cancelled) => return Err(Stop::new(Status::Aborted, "cancelled")),
            Err(e) if wanted => {
                self.warnings.push(format!("flying without the geofence: {e}"));
                return Ok(());
            }
            Err(e) => {
                self.warnings.push(format!("could not clear an old geofence: {e}"));
                return Ok(());
            }
        }
        let p = ParamSet::new(
            self.target,
            vec![("GF_ACTION".into(), GF_WARNING_ONLY)],
            RetryPolicy::PARAM,
        );
        match self.link.exchange(p, &self.cancel).await {
            Ok(changes) => {
                self.fence_uploaded = true;
                self.restore
                    .extend(changes.into_iter().filter(|c| c.old != c.new).map(|c| (c.name, c.old)));
                Ok(())
            }
            Err(ProtocolError::Cancelled) => Err(Stop::new(Status::Aborted, "cancelled")),
            Err(e) => {
                // A fence that may act (e.g. Hold) would steer the test: take it away again.
                self.warnings
                    .push(format!("GF_ACTION not set to warning-only ({e}); fence removed"));
                let clear = MissionUpload::new(self.target, ty, Vec::new(), RetryPolicy::MISSION);
                if let Err(e) = self.link.exchange(clear, &self.cancel).await {
                    return Err(stop_for("removing the geofence", e));
                }
                Ok(())
            }
        }
    }

    /// LOCAL_POSITION_NED at [`POSITION_RATE_HZ`]; ATTITUDE as fast, for the heading. Refusals are warnings.
    async fn request_streams(&mut self) {
        let mut streams = vec![(32.0, POSITION_RATE_HZ), (30.0, POSITION_RATE_HZ)];
        if self.opts.sim_gate.is_some() && self.opts.mode == FlyMode::Avoidance {
            // On simulated time the companion answers the newest request at each hold: at PX4's 5 Hz the
            // request it has would be up to 200 ms old, by when the stream happened to tick.
            streams.push((f32::from(TRAJECTORY_REPRESENTATION_WAYPOINTS_ID), REQUEST_RATE_HZ));
        }
        for (id, hz) in streams {
            let p = [id, (1e6 / hz) as f32, 0.0, 0.0, 0.0, 0.0, 0.0];
            if let Err(e) = self.command(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, p).await {
                self.warnings.push(format!("message {id} at {hz} Hz: {e}"));
            }
        }
    }

    /// Puts back changed parameters (bounded; a failure is a warning).
    pub async fn restore_params(&mut self) {
        if self.restore.is_empty() {
            return;
        }
        let quick = RetryPolicy {
            timeout: Duration::from_secs(1),
            max_retries: 2,
        };
        let p = ParamSet::new(self.target, std::mem::take(&mut self.restore), quick);
        if let Err(e) = self.link.exchange(p, &CancelToken::new()).await {
            self.warnings.push(format!("could not restore parameters: {e}"));
        }
    }
}
