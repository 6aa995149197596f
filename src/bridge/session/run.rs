//! One flight from connection to report: find and lock onto the vehicle, heartbeat, set the parameters,
//! upload and check the mission, upload the obstacles as a geofence, wait for home, then hand over to
//! [`super::flight`] and finally restore what was changed. Vehicle refusals end in a report, not an error.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use mavlink::dialects::common::{HEARTBEAT_DATA, MavAutopilot, MavMessage, MavModeFlag, MavState, MavType};
use tokio::sync::broadcast;

use super::clock_watch::ClockReport;
use super::context::{Readiness, Session, Stop};
use super::flight;
use super::recorder::Recorder;
use super::report::{Ending, FlightReport, Status};
use super::tasks::Tasks;
use crate::bridge::options::{BridgeError, FlyOptions};
use crate::bridge::wire::cancel::CancelToken;
use crate::bridge::wire::clock::{VehicleClock, secs};
use crate::bridge::wire::exchange::Target;
use crate::bridge::wire::link::{Inbound, Link, Sender, Transport};
use crate::bridge::wire::vehicle::VehicleView;
use crate::model::TestCase;

/// Runs one flight on `transport`.
pub async fn run(
    test: &TestCase,
    opts: &FlyOptions,
    transport: Arc<dyn Transport>,
    cancel: CancelToken,
) -> Result<FlightReport, BridgeError> {
    let mut recorder = Recorder::create(opts.trajectory_csv.as_deref()).map_err(|source| BridgeError::Trajectory {
        path: opts.trajectory_csv.clone().unwrap_or_default(),
        source,
    })?;
    // The test re-anchored at the vehicle's home, if asked (it must outlive the session that borrows it).
    let anchored = std::sync::OnceLock::new();
    let (mut s, clock_report) = connect(test, opts, transport, cancel).await?;
    s.ready.started = Some(s.link.clock().now());
    let stop = match s.check_hitl().await {
        Ok(()) => match s.place(&anchored).await {
            Ok(()) => match s.prepare().await {
                Ok(()) => flight::follow(&mut s, &mut recorder).await,
                Err(stop) => stop,
            },
            Err(stop) => stop,
        },
        Err(stop) => stop,
    };
    s.restore_params().await;
    // Let go of the link before reporting: its tasks end, then its receive task (see `Link::close`).
    s.tasks.shutdown().await;
    s.link.close().await;
    let clock = clock_report.lock().map(|c| c.clone()).ok();
    Ok(report(s, stop, recorder, clock))
}

/// Opens the link, waits for the vehicle and locks onto it, and starts the session's background tasks (our
/// heartbeat, the clock watch, the vehicle's texts); returns the session and the clock watch's report.
async fn connect<'a>(
    test: &'a TestCase,
    opts: &'a FlyOptions,
    transport: Arc<dyn Transport>,
    cancel: CancelToken,
) -> Result<(Session<'a>, Arc<Mutex<ClockReport>>), BridgeError> {
    let clock = VehicleClock::new(opts.time_scale);
    let link = Arc::new(Link::new(transport, clock));
    let mut tasks = Tasks::default();
    tasks.push(tokio::spawn(gcs_heartbeat(link.clone())));
    let mut rx = link.subscribe();
    // Subscribed before the heartbeat wait, so nothing the vehicle says from the start is missed.
    let texts_rx = link.subscribe();
    let (target, heartbeat) = wait_heartbeat(&mut rx, opts, &cancel).await?;
    link.lock(target.system);
    let companion_beat_from = (opts.mode == crate::bridge::FlyMode::Avoidance).then(|| {
        tasks.push(crate::bridge::companion::avoidance::spawn_heartbeat(link.clone()));
        link.clock().now()
    });
    // Its own receiver: the session's keeps every message the vehicle sends meanwhile. The release decides
    // which modes and parameters this vehicle has (see `capability`).
    let mut answers = link.subscribe();
    let flight_sw = super::identify::flight_sw_version(&link, &mut answers, target, &cancel).await;
    let identity = super::identify::identity(target, &heartbeat, flight_sw);
    if let Some(sink) = &opts.notices {
        (sink.0)(&crate::bridge::wire::notices::Notice::Answered(identity.to_string()));
    }
    let clock_report = super::clock_watch::start(&link, opts, &mut tasks).await;
    let messages = crate::bridge::wire::notices::Messages::default();
    tasks.push(crate::bridge::wire::notices::spawn_collector(
        texts_rx,
        link.clock(),
        messages.clone(),
        opts.notices.clone(),
    ));
    let s = Session {
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
        mpc_xy_cruise_m_s: None,
        ready: Readiness::default(),
        px4_version: super::identify::px4_version(&heartbeat, flight_sw),
        identity,
        companion_beat_from,
    };
    Ok((s, clock_report))
}

/// The report of a finished session: the recording judged, with every warning and how the flight ended.
fn report(mut s: Session<'_>, stop: Stop, mut recorder: Recorder, clock: Option<ClockReport>) -> FlightReport {
    let trajectory = recorder.finish();
    if let Some(e) = recorder.write_error() {
        s.warnings.push(format!("trajectory CSV incomplete: {e}"));
    }
    if let Some(w) = s.companion.warning() {
        s.warnings.push(w);
    }
    s.view.flush_texts();
    let mut warnings = std::mem::take(&mut s.view.warnings);
    warnings.append(&mut s.warnings);
    let mut reason = stop.reason;
    // A refusal quotes the vehicle's own last words, if it said anything and they are not quoted yet.
    if stop.status == Status::Rejected
        && !reason.contains("vehicle")
        && let Some(said) = crate::bridge::wire::notices::last_texts(&s.messages, 3)
    {
        reason = format!("{reason}; vehicle: {said}");
    }
    let reason = (stop.status != Status::Landed).then_some(reason);
    let vehicle_messages = s.messages.lock().map(|m| m.clone()).unwrap_or_default();
    let opts = s.opts;
    let cp_dist = (opts.mode == crate::bridge::FlyMode::CollisionPrevention)
        .then(|| crate::lfs::cp_params::CpParams::from_params(&s.test.params).ok())
        .flatten();
    let mut report = FlightReport::judge(
        trajectory,
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
            companion_timing: s.companion.timing.report(),
            planner_cruise_m_s: s.mpc_xy_cruise_m_s,
            vehicle: Some(s.identity.clone()),
        },
    );
    report.collision_prevention =
        cp_dist.map(|c| crate::judge::cp_verdict::cp_verdict(&report.trajectory, &s.test.obstacles, c.dist_m));
    report.companion_answers = s.companion.counts();
    report
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

/// Waits (bounded) for an autopilot's heartbeat: the vehicle to fly, and what its heartbeat says.
async fn wait_heartbeat(
    rx: &mut broadcast::Receiver<Arc<Inbound>>,
    opts: &FlyOptions,
    cancel: &CancelToken,
) -> Result<(Target, HEARTBEAT_DATA), BridgeError> {
    let deadline = Instant::now() + secs(opts.heartbeat_wait_s);
    loop {
        let wait = deadline.saturating_duration_since(Instant::now());
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
                        return Ok((Target { system, component: inb.header.component_id }, h.clone()));
                    }
                }
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => tokio::time::sleep(wait).await,
            },
            _ = tokio::time::sleep(wait) => {
                return Err(BridgeError::NoHeartbeat { url: opts.connect.clone(), waited_s: opts.heartbeat_wait_s });
            }
        }
        if Instant::now() >= deadline {
            return Err(BridgeError::NoHeartbeat {
                url: opts.connect.clone(),
                waited_s: opts.heartbeat_wait_s,
            });
        }
    }
}
