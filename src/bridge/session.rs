//! One flight from connection to report: find and lock onto the vehicle, heartbeat, set the parameters,
//! upload and check the mission, upload the obstacles as a geofence, wait for home, then hand over to
//! [`super::flight`] and finally restore what was changed. Vehicle refusals end in a report, not an error.
#![allow(deprecated)]

use std::sync::Arc;
use std::time::Duration;

use mavlink::dialects::common::{
    HEARTBEAT_DATA, MavAutopilot, MavCmd, MavMessage, MavMissionType, MavModeFlag, MavState, MavType,
};
use tokio::sync::broadcast;
use tokio::task::JoinHandle;

use super::cancel::CancelToken;
use super::clock::{VehicleClock, secs};
use super::command::Command;
use super::exchange::{ProtocolError, Retry, Target};
use super::link::{Inbound, Link, Sender, Transport};
use super::mission_download::MissionDownload;
use super::mission_upload::MissionUpload;
use super::params::ParamSet;
use super::plan_items::{fence_items, first_difference, mission_items};
use super::recorder::Recorder;
use super::report::{Ending, FlightReport, Status};
use super::vehicle::VehicleView;
use super::{BridgeError, FlyMode, FlyOptions, flight};
use crate::model::{LocalProjection, TestCase};

/// GF_ACTION = 1: the fence only warns, so it never steers the test.
const GF_WARNING_ONLY: f64 = 1.0;
/// LOCAL_POSITION_NED rate requested, Hz (the issue asks for at least 30).
pub const POSITION_RATE_HZ: f64 = 50.0;

/// Why the session stopped before or during the flight.
#[derive(Debug, Clone, PartialEq)]
pub struct Stop {
    /// Status to report.
    pub status: Status,
    /// Why, in words.
    pub reason: String,
}

impl Stop {
    /// A stop with `status` and `reason`.
    pub fn new(status: Status, reason: impl Into<String>) -> Self {
        Self {
            status,
            reason: reason.into(),
        }
    }
}

/// Maps a failed exchange to the report status: refusals are `rejected`, silence is `link_lost`.
pub fn stop_for(what: &str, e: ProtocolError) -> Stop {
    let status = match e {
        ProtocolError::Timeout { .. } => Status::LinkLost,
        ProtocolError::Cancelled => Status::Aborted,
        _ => Status::Rejected,
    };
    Stop::new(status, format!("{what}: {e}"))
}

/// Aborts its tasks when dropped, so no task outlives the flight.
#[derive(Default)]
pub struct Tasks(Vec<JoinHandle<()>>);

impl Tasks {
    /// Keeps `t` until the end of the flight.
    pub fn push(&mut self, t: JoinHandle<()>) {
        self.0.push(t);
    }
}

impl Drop for Tasks {
    fn drop(&mut self) {
        for t in &self.0 {
            t.abort();
        }
    }
}

/// Everything the steps of a flight share.
pub struct Session<'a> {
    /// The link.
    pub link: Arc<Link>,
    /// The vehicle.
    pub target: Target,
    /// Options.
    pub opts: &'a FlyOptions,
    /// The test.
    pub test: &'a TestCase,
    /// The user's cancel.
    pub cancel: CancelToken,
    /// Our subscription for following the vehicle.
    pub rx: broadcast::Receiver<Arc<Inbound>>,
    /// The vehicle as last heard.
    pub view: VehicleView,
    /// The bridge's own warnings.
    pub warnings: Vec<String>,
    /// Geofence on the vehicle.
    pub fence_uploaded: bool,
    /// Parameters to put back at the end (name, old value).
    pub restore: Vec<(String, f64)>,
    /// Background tasks.
    pub tasks: Tasks,
    /// The avoidance companion's answer counts (avoidance mode).
    pub companion: Arc<super::avoidance::CompanionStats>,
    /// PX4's local frame -> the test's frame, once measured ([`super::placement`]).
    pub frame: Option<super::frame::TestFrame>,
    /// Where the vehicle stood against the test's home, once known.
    pub placement: Option<super::placement::Placement>,
    /// The vehicle's STATUSTEXT of severity WARNING or worse, as they arrived.
    pub messages: super::notices::Messages,
    /// Readiness timing and the arming budget.
    pub ready: super::ready::Readiness,
}

/// Runs one flight on `transport`.
pub async fn run(
    test: &TestCase,
    opts: &FlyOptions,
    transport: Arc<dyn Transport>,
    cancel: CancelToken,
) -> Result<FlightReport, BridgeError> {
    let recorder = Recorder::create(opts.trajectory_csv.as_deref()).map_err(|source| BridgeError::Trajectory {
        path: opts.trajectory_csv.clone().unwrap_or_default(),
        source,
    })?;
    let clock = VehicleClock::new(opts.time_scale);
    let link = Arc::new(Link::new(transport, clock));
    let mut tasks = Tasks::default();
    tasks.push(tokio::spawn(gcs_heartbeat(link.clone())));
    let mut rx = link.subscribe();
    // Subscribed before the heartbeat wait, so nothing the vehicle says from the start is missed.
    let texts_rx = link.subscribe();
    let target = wait_heartbeat(&link, &mut rx, opts, &cancel).await?;
    link.lock(target.system);
    // The test re-anchored at the vehicle's home, if asked (it must outlive the session that borrows it).
    let anchored = std::sync::OnceLock::new();
    let clock_report = super::clock_watch::start(&link, opts, &mut tasks).await;
    let messages = super::notices::Messages::default();
    tasks.push(super::notices::spawn_collector(
        texts_rx,
        link.clock(),
        messages.clone(),
        opts.notices.clone(),
    ));
    let mut s = Session {
        link,
        target,
        opts,
        test,
        cancel,
        rx,
        view: VehicleView::default(),
        warnings: Vec::new(),
        fence_uploaded: false,
        restore: Vec::new(),
        tasks,
        companion: Arc::default(),
        frame: None,
        placement: None,
        messages,
        ready: super::ready::Readiness::default(),
    };
    let mut recorder = recorder;
    s.ready.started = Some(s.link.clock().now());
    let stop = match s.place(&anchored).await {
        Ok(()) => match s.prepare().await {
            Ok(()) => flight::follow(&mut s, &mut recorder).await,
            Err(stop) => stop,
        },
        Err(stop) => stop,
    };
    s.restore_params().await;
    if let Some(e) = recorder.write_error() {
        s.warnings.push(format!("trajectory CSV incomplete: {e}"));
    }
    if let Some(w) = s.companion.warning() {
        s.warnings.push(w);
    }
    let mut warnings = std::mem::take(&mut s.view.warnings);
    warnings.append(&mut s.warnings);
    let mut reason = stop.reason;
    // A refusal quotes the vehicle's own last words, if it said anything and they are not quoted yet.
    if stop.status == Status::Rejected
        && !reason.contains("vehicle")
        && let Some(said) = super::notices::last_texts(&s.messages, 3)
    {
        reason = format!("{reason}; vehicle: {said}");
    }
    let reason = (stop.status != Status::Landed).then_some(reason);
    let vehicle_messages = s.messages.lock().map(|m| m.clone()).unwrap_or_default();
    let clock = clock_report.lock().map(|c| c.clone()).ok();
    Ok(FlightReport::judge(
        recorder.trajectory(),
        &s.test.obstacles,
        Ending {
            judge: opts.judge,
            frame: s.frame,
            placement: s.placement.take(),
            status: stop.status,
            reason,
            mode: opts.mode,
            fence_uploaded: s.fence_uploaded,
            warnings,
            link: s.link.stats(),
            lfs_min_distance: opts.lfs_min_distance,
            ready_wait_s: s.ready.waited_s,
            vehicle_messages,
            clock,
        },
    ))
}

/// Our ground-station heartbeat at 1 Hz (vehicle time) for the whole session.
async fn gcs_heartbeat(link: Arc<Link>) {
    let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    });
    loop {
        // udpin cannot send before the vehicle spoke; that is fine, the next beat goes out.
        let _ = link.send(Sender::Gcs, &hb).await;
        tokio::time::sleep(link.clock().wall(Duration::from_secs(1))).await;
    }
}

/// Waits (bounded) for an autopilot's heartbeat: the vehicle to fly.
async fn wait_heartbeat(
    link: &Link,
    rx: &mut broadcast::Receiver<Arc<Inbound>>,
    opts: &FlyOptions,
    cancel: &CancelToken,
) -> Result<Target, BridgeError> {
    let deadline = link.clock().now() + secs(opts.heartbeat_wait_s);
    loop {
        let wait = link.clock().wall_until(deadline);
        tokio::select! {
            biased;
            _ = cancel.cancelled() => return Err(BridgeError::Cancelled),
            r = rx.recv() => match r {
                Ok(inb) => {
                    let system = inb.header.system_id.min(255) as u8;
                    if let MavMessage::HEARTBEAT(h) = &inb.msg
                        && h.autopilot != MavAutopilot::MAV_AUTOPILOT_INVALID
                        && opts.target_system.is_none_or(|t| t == system)
                    {
                        return Ok(Target { system, component: inb.header.component_id });
                    }
                }
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => tokio::time::sleep(wait).await,
            },
            _ = tokio::time::sleep(wait) => {
                return Err(BridgeError::NoHeartbeat { url: opts.connect.clone(), waited_s: opts.heartbeat_wait_s });
            }
        }
        if link.clock().now() >= deadline {
            return Err(BridgeError::NoHeartbeat {
                url: opts.connect.clone(),
                waited_s: opts.heartbeat_wait_s,
            });
        }
    }
}

impl Session<'_> {
    /// Folds every message received so far into the view.
    pub fn drain(&mut self) {
        let now = self.link.clock().now();
        loop {
            match self.rx.try_recv() {
                Ok(inb) => self.view.update(&inb.msg, now),
                Err(broadcast::error::TryRecvError::Lagged(_)) => {}
                Err(_) => break,
            }
        }
    }

    /// Runs a command to its ACK.
    pub async fn command(&self, cmd: MavCmd, params: [f32; 7]) -> Result<(), ProtocolError> {
        let c = Command::new(self.target, cmd, params, Retry::COMMAND);
        self.link.exchange(c, &self.cancel).await
    }

    /// Everything before the first command of the flight.
    async fn prepare(&mut self) -> Result<(), Stop> {
        if self.opts.mode == FlyMode::Avoidance {
            let steer = super::flight::steer_for(self.test, self.opts, self.frame);
            let pacing = match self.opts.lockstep {
                Some(latency) => super::avoidance::Pacing::Lockstep { latency },
                None => super::avoidance::Pacing::FreeRunning,
            };
            let companion = self.companion.clone();
            for t in super::avoidance::spawn(self.link.clone(), self.target, steer, companion, pacing) {
                self.tasks.push(t);
            }
        }
        self.set_params().await?;
        self.upload_mission().await?;
        self.upload_fence().await?;
        self.request_streams().await;
        let mut st = super::ready::ReadyState::default();
        super::ready::wait_ready(self, &mut st).await
    }

    async fn set_params(&mut self) -> Result<(), Stop> {
        let avoid = if self.opts.mode == FlyMode::Avoidance { 1.0 } else { 0.0 };
        let mut wanted: Vec<(String, f64)> = self
            .test
            .params
            .iter()
            .filter(|p| p.name != "COM_OBS_AVOID")
            .map(|p| (p.name.clone(), p.value))
            .collect();
        wanted.push(("COM_OBS_AVOID".into(), avoid));
        let p = ParamSet::new(self.target, wanted, Retry::PARAM);
        self.link
            .exchange(p, &self.cancel)
            .await
            .map(|_| ())
            .map_err(|e| stop_for("setting the case-study parameters", e))
    }

    async fn upload_mission(&mut self) -> Result<(), Stop> {
        let items = mission_items(&self.test.mission).map_err(|e| Stop::new(Status::Rejected, e))?;
        let ty = MavMissionType::MAV_MISSION_TYPE_MISSION;
        let up = MissionUpload::new(self.target, ty, items.clone(), Retry::MISSION);
        self.link
            .exchange(up, &self.cancel)
            .await
            .map_err(|e| stop_for("uploading the mission", e))?;
        self.ready.mission_uploaded_at = Some(self.link.clock().now());
        let down = MissionDownload::new(self.target, ty, Retry::MISSION);
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
        let up = MissionUpload::new(self.target, ty, items, Retry::MISSION);
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
        let p = ParamSet::new(self.target, vec![("GF_ACTION".into(), GF_WARNING_ONLY)], Retry::PARAM);
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
                let clear = MissionUpload::new(self.target, ty, Vec::new(), Retry::MISSION);
                if let Err(e) = self.link.exchange(clear, &self.cancel).await {
                    return Err(stop_for("removing the geofence", e));
                }
                Ok(())
            }
        }
    }

    /// LOCAL_POSITION_NED at [`POSITION_RATE_HZ`]; ATTITUDE as fast, for the heading. Refusals are warnings.
    async fn request_streams(&mut self) {
        let interval_us = (1e6 / POSITION_RATE_HZ) as f32;
        for id in [32.0, 30.0] {
            let p = [id, interval_us, 0.0, 0.0, 0.0, 0.0, 0.0];
            if let Err(e) = self.command(MavCmd::MAV_CMD_SET_MESSAGE_INTERVAL, p).await {
                self.warnings
                    .push(format!("message {id} at {POSITION_RATE_HZ} Hz: {e}"));
            }
        }
    }

    /// Waits (bounded by the readiness budget, at least 30 s vehicle time) for HOME_POSITION, asking for it once.
    pub(super) async fn wait_home(&mut self) -> Result<(), Stop> {
        self.drain();
        if self.view.home_known {
            return Ok(());
        }
        let p = [242.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        if let Err(e) = self.command(MavCmd::MAV_CMD_REQUEST_MESSAGE, p).await {
            self.warnings.push(format!("requesting HOME_POSITION: {e}"));
        }
        let clock = self.link.clock();
        // Home comes once the estimator has a fix: the readiness budget, not a fixed wait.
        let budget = Duration::from_secs_f64(self.opts.ready_timeout_s.max(30.0));
        let deadline = clock.now() + budget;
        while !self.view.home_known {
            let wait = clock.wall_until(deadline);
            tokio::select! {
                biased;
                _ = self.cancel.cancelled() => return Err(Stop::new(Status::Aborted, "cancelled while waiting for home")),
                r = self.rx.recv() => match r {
                    Ok(inb) => self.view.update(&inb.msg, clock.now()),
                    Err(broadcast::error::RecvError::Lagged(_)) => {}
                    Err(broadcast::error::RecvError::Closed) => tokio::time::sleep(wait).await,
                },
                _ = tokio::time::sleep(wait) => {
                    return Err(Stop::new(Status::Rejected, format!("no home position within {} s (no GPS fix?)", budget.as_secs())));
                }
            }
        }
        Ok(())
    }

    /// Puts back changed parameters (bounded; a failure is a warning).
    async fn restore_params(&mut self) {
        if self.restore.is_empty() {
            return;
        }
        let quick = Retry {
            timeout: Duration::from_secs(1),
            max_retries: 2,
        };
        let p = ParamSet::new(self.target, std::mem::take(&mut self.restore), quick);
        if let Err(e) = self.link.exchange(p, &CancelToken::new()).await {
            self.warnings.push(format!("could not restore parameters: {e}"));
        }
    }
}
