//! The obstacle-avoidance companion of PX4 <= 1.15 (COM_OBS_AVOID = 1): heartbeats as component 196 with the
//! vehicle's system id (MAV_TYPE_ONBOARD_CONTROLLER, MAV_STATE_ACTIVE), reads PX4's desired trajectory
//! (TRAJECTORY_REPRESENTATION_WAYPOINTS: point 0 PX4's setpoint with its type in `command[0]`, 1 the current
//! item, 2 the next) and answers at 10 Hz with point 0 = the planner's setpoint, or PX4's own setpoint
//! mirrored when it cannot plan. Goals, takeoff and land follow PX4-Avoidance (see [`Companion::on_request`]):
//! while landing the answer is PX4's own kind of land setpoint (x, y held, z unset, descent velocity), which is
//! what lets PX4's land detector see the vehicle resting with low thrust and disarm.

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
use mavlink::dialects::common::{
    HEARTBEAT_DATA, MavAutopilot, MavMessage, MavModeFlag, MavState, MavType, TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA,
};
use tokio::sync::broadcast;
use tokio::task::JoinHandle;

use super::answers::AnswerCounts;
use super::pose_history::PoseHistory;
use super::steer::{Nav, Steer, SteerInput, SteerOutput};
use super::steer_worker::SteerWorker;
use super::timing::AnswerTiming;
pub use super::trajectory_points::empty_trajectory;
use super::trajectory_points::{point, point_xy, velocity_axes};
use crate::bridge::wire::exchange::Target;
use crate::bridge::wire::link::{AVOIDANCE_COMPONENT_ID, Link, Sender};
use crate::bridge::wire::vehicle::VehicleView;

/// Answer period (10 Hz, as PX4-Avoidance's waypoint generator).
pub const ANSWER_PERIOD: Duration = Duration::from_millis(100);
/// Companion heartbeat period (PX4 declares the companion lost after 5 s without one).
pub const HEARTBEAT_PERIOD: Duration = Duration::from_millis(500);
/// A planner result computed from inputs older than this is not sent (PX4 itself gives up after 0.5 s).
pub const STALE_PLAN: Duration = Duration::from_millis(500);
/// A request older than this means PX4 left the auto modes: stop answering.
pub const REQUEST_STALE: Duration = Duration::from_secs(1);

const MAV_CMD_NAV_LAND: u16 = 21;
const MAV_CMD_NAV_TAKEOFF: u16 = 22;

/// The companion's memory: PX4's latest request and the goal it implies, kept as PX4-Avoidance's
/// `fcuInputGoalCallback` (local_planner_nodelet.cpp) keeps them.
#[derive(Debug, Clone, Default)]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
pub struct Companion {
    request: Option<(TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA, Duration)>,
    /// The goal; its z may be NaN while landing (PX4's land setpoint leaves z unset).
    goal: Option<[f64; 3]>,
    prev_goal: Option<[f64; 3]>,
    /// PX4's point-0 velocity latched with the goal (the descent speed while landing).
    desired_vel: Option<[f64; 3]>,
    /// Point 1 (the current mission item) as last seen: a new item is what makes a new goal.
    mission_item: Option<[f64; 3]>,
    nav: Option<Nav>,
    /// Answers sent that mirrored PX4's setpoint.
    pub mirrored: u64,
    /// Answers sent from the planner.
    pub planned: u64,
}

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
impl Companion {
    /// A request from PX4 at vehicle time `now`.
    ///
    /// As PX4-Avoidance: when the current item (point 1) moved by more than 1 cm, the goal becomes PX4's own
    /// setpoint (point 0, with its velocity), and the takeoff and land flags come from point 0's command; a
    /// current item that is a plain position (`command[1]` unset) is itself the goal.
    pub fn on_request(&mut self, t: &TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA, now: Duration) {
        let valid = |i: usize| usize::from(t.valid_points) > i;
        let p1 = valid(1).then(|| point(t, 1)).flatten();
        let moved = match (p1, self.mission_item) {
            (Some(p), Some(m)) => dist(&p, &m) > 0.01,
            (Some(_), None) => true,
            (None, _) => false,
        };
        if valid(0)
            && (moved || self.goal.is_none())
            && let Some(g) = point_xy(t, 0)
        {
            self.prev_goal = self.goal.or(Some(g));
            self.goal = Some(g);
            self.desired_vel = velocity_axes(t, 0);
            self.nav = Some(match t.command[0] {
                MAV_CMD_NAV_TAKEOFF => Nav::Takeoff,
                MAV_CMD_NAV_LAND => Nav::Land,
                _ => Nav::Mission,
            });
        }
        if let Some(p) = p1 {
            self.mission_item = Some(p);
            if t.command[1] == u16::MAX {
                if self.goal.is_none() {
                    self.prev_goal = Some(p);
                }
                self.goal = Some(p);
                self.desired_vel = None;
            }
        }
        self.request = Some((t.clone(), now));
    }

    /// The steering question at vehicle time `now`, if PX4 is asking and the pose is known.
    pub fn steer_input(&self, view: &VehicleView, now: Duration) -> Option<SteerInput> {
        let (_, at) = self.request.as_ref()?;
        if now.saturating_sub(*at) > REQUEST_STALE {
            return None;
        }
        let (pose, goal) = (view.pose?, self.goal?);
        Some(SteerInput {
            now_s: now.as_secs_f64(),
            pos_ned: pose.pos_ned,
            vel_ned: pose.vel_ned,
            yaw_rad: pose.yaw_rad.unwrap_or(0.0),
            goal_ned: goal,
            prev_goal_ned: self.prev_goal.unwrap_or(goal),
            desired_vel_ned: self.desired_vel,
            nav: self.nav.unwrap_or(Nav::Mission),
            airborne: view.armed,
        })
    }

    /// Steers and answers in one go (see [`Companion::answer_with`]).
    pub fn answer(
        &mut self,
        view: &VehicleView,
        steer: &mut dyn Steer,
        now: Duration,
        time_usec: u64,
    ) -> Option<TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA> {
        let planned = self.steer_input(view, now).and_then(|i| steer.steer(&i));
        self.answer_with(planned, now, time_usec)
    }

    /// The answer with `planned` as point 0, or PX4's own point 0 mirrored when `None`; `None` when PX4 is not
    /// asking (no fresh request).
    pub fn answer_with(
        &mut self,
        planned: Option<SteerOutput>,
        now: Duration,
        time_usec: u64,
    ) -> Option<TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA> {
        let (req, at) = self.request.clone()?;
        if now.saturating_sub(at) > REQUEST_STALE {
            return None;
        }
        let mut out = empty_trajectory(time_usec, 1);
        match planned {
            Some(sp) => {
                self.planned += 1;
                out.pos_x[0] = sp.pos_ned[0] as f32;
                out.pos_y[0] = sp.pos_ned[1] as f32;
                out.pos_z[0] = sp.pos_ned[2] as f32;
                let [vx, vy, vz] = sp.vel_ned.map(|v| v.map_or(f32::NAN, |v| v as f32));
                (out.vel_x[0], out.vel_y[0], out.vel_z[0]) = (vx, vy, vz);
                out.pos_yaw[0] = sp.yaw_rad.map_or(f32::NAN, |y| y as f32);
                out.vel_yaw[0] = sp.yaw_rate_rad_s.map_or(f32::NAN, |r| r as f32);
            }
            None => {
                // Mirror PX4's point 0 (position and/or velocity): the interface's "cannot plan" answer.
                self.mirrored += 1;
                for (dst, src) in [
                    (&mut out.pos_x, &req.pos_x),
                    (&mut out.pos_y, &req.pos_y),
                    (&mut out.pos_z, &req.pos_z),
                    (&mut out.vel_x, &req.vel_x),
                    (&mut out.vel_y, &req.vel_y),
                    (&mut out.vel_z, &req.vel_z),
                    (&mut out.pos_yaw, &req.pos_yaw),
                ] {
                    dst[0] = src[0];
                }
            }
        }
        Some(out)
    }
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The companion's heartbeat.
pub fn heartbeat() -> MavMessage {
    MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_ONBOARD_CONTROLLER,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    })
}

/// How the companion answered, shared with the session so the flight report can say when the planner fell
/// behind (a mirrored answer means PX4 flew its own setpoint, i.e. no avoidance).
#[derive(Debug, Default)]
pub struct CompanionStats {
    /// Answers from the planner.
    pub planned: AtomicU64,
    /// Answers that mirrored PX4's setpoint.
    pub mirrored: AtomicU64,
    /// Wall-time latencies of the answers.
    pub timing: AnswerTiming,
}

impl CompanionStats {
    /// The answers sent so far (`None`: none, e.g. no companion ran).
    pub fn counts(&self) -> Option<AnswerCounts> {
        let c = AnswerCounts {
            planned: self.planned.load(Ordering::Relaxed),
            mirrored: self.mirrored.load(Ordering::Relaxed),
        };
        (c.total() > 0).then_some(c)
    }

    /// A report warning when the flight was starved ([`AnswerCounts::starved`]).
    pub fn warning(&self) -> Option<String> {
        let c = self.counts().filter(AnswerCounts::starved)?;
        Some(format!(
            "{}: the machine did not keep up (fewer instances, or a lower speed factor)",
            c.describe()
        ))
    }
}

/// The companion's heartbeat until aborted: started as soon as the vehicle answers, seconds of vehicle time
/// before COM_OBS_AVOID is set, so PX4 (which rates a companion's heartbeats about once a second) never
/// runs its pre-flight check with the avoidance system missing.
pub fn spawn_heartbeat(link: Arc<Link>) -> JoinHandle<()> {
    tokio::spawn(beat(link))
}

/// Sends the companion's answers and publishes their counts and timing.
pub(super) struct Answers {
    link: Arc<Link>,
    stats: Arc<CompanionStats>,
    /// Wall instant of the oldest request not answered yet.
    asked: Option<Instant>,
}

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
impl Answers {
    /// Answers on `link`, counted in `stats`.
    pub(super) fn new(link: Arc<Link>, stats: Arc<CompanionStats>) -> Self {
        Self {
            link,
            stats,
            asked: None,
        }
    }

    /// A request arrived now (only the oldest unanswered one is timed).
    pub(super) fn asked(&mut self) {
        self.asked.get_or_insert_with(Instant::now);
    }

    /// Sends the answer to PX4's latest request (if it is still asking) with `planned`, the latest result of
    /// `worker`, at vehicle time `now`.
    pub(super) async fn send(
        &mut self,
        companion: &mut Companion,
        worker: &mut SteerWorker,
        planned: Option<SteerOutput>,
        now: Duration,
        time_usec: u64,
    ) {
        let stats = &self.stats;
        for t in worker.take_plan_times() {
            stats.timing.plan(t);
        }
        let Some(a) = companion.answer_with(planned, now, time_usec) else {
            return;
        };
        stats.planned.store(companion.planned, Ordering::Relaxed);
        stats.mirrored.store(companion.mirrored, Ordering::Relaxed);
        let _ = self
            .link
            .send(Sender::Companion, &MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(a))
            .await;
        let sent = Instant::now();
        if let Some(at) = self.asked.take() {
            stats.timing.request_to_answer(sent.saturating_duration_since(at));
        }
        if planned.is_some()
            && let Some(input) = worker.latest_input_wall()
        {
            stats.timing.plan_age(sent.saturating_duration_since(input));
        }
    }
}

/// Whether a message with this header is PX4's request (not our own answer echoed back).
pub(super) fn is_request(inb_header: &mavlink::MavHeader, target: Target) -> bool {
    inb_header.component_id != AVOIDANCE_COMPONENT_ID && inb_header.system_id == u32::from(target.system)
}

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
pub(super) async fn run_lockstep(
    link: Arc<Link>,
    target: Target,
    steer: Box<dyn Steer>,
    stats: Arc<CompanionStats>,
    latency: Duration,
) {
    let clock = link.clock();
    let mut rx = link.subscribe();
    let mut view = VehicleView::default();
    let mut history = PoseHistory::default();
    let mut companion = Companion::default();
    let mut worker = SteerWorker::new(steer);
    let mut answers = Answers::new(link.clone(), stats);
    loop {
        let inb = match rx.recv().await {
            Ok(inb) => inb,
            Err(broadcast::error::RecvError::Lagged(_)) => continue,
            Err(broadcast::error::RecvError::Closed) => return,
        };
        let MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(t) = &inb.msg else {
            view.update(&inb.msg, clock.now());
            if matches!(inb.msg, MavMessage::LOCAL_POSITION_NED(_)) {
                history.push(view.pose);
            }
            continue;
        };
        if !is_request(&inb.header, target) {
            continue;
        }
        answers.asked();
        // The vehicle's own time: the request was sent at it and the vehicle waits for the answer.
        let now = Duration::from_micros(t.time_usec);
        companion.on_request(t, now);
        // Plan on the pose `latency` old: swapped in for the question only (no copy of the whole view).
        let current = view.pose;
        view.pose = history.at(now.saturating_sub(latency)).or(current);
        let input = companion.steer_input(&view, now);
        view.pose = current;
        let planned = match input {
            Some(input) => match worker.compute(input, now).await {
                Some(out) => out,
                None => return,
            },
            None => None,
        };
        answers
            .send(&mut companion, &mut worker, planned, now, t.time_usec)
            .await;
    }
}

async fn beat(link: Arc<Link>) {
    loop {
        let _ = link.send(Sender::Companion, &heartbeat()).await;
        tokio::time::sleep(link.clock().wall(HEARTBEAT_PERIOD)).await;
    }
}

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
pub(super) async fn run(link: Arc<Link>, target: Target, steer: Box<dyn Steer>, stats: Arc<CompanionStats>) {
    let clock = link.clock();
    let mut rx = link.subscribe();
    let mut view = VehicleView::default();
    let mut companion = Companion::default();
    let mut worker = SteerWorker::new(steer);
    let mut next_answer = clock.now();
    let mut answers = Answers::new(link.clone(), stats);
    loop {
        let now = clock.now();
        if now >= next_answer {
            next_answer = now + ANSWER_PERIOD;
            if !worker.poll(companion.steer_input(&view, now), now).await {
                return;
            }
            // A plan older than PX4's own patience (0.5 s) is not used: mirror instead.
            let planned = worker.latest(now, STALE_PLAN).flatten();
            let usec = view.pose.map_or(0, |p| u64::from(p.time_boot_ms) * 1000);
            answers.send(&mut companion, &mut worker, planned, now, usec).await;
        }
        let wake = clock.wall_until(next_answer);
        tokio::select! {
            r = rx.recv() => match r {
                Ok(inb) => {
                    let now = clock.now();
                    match &inb.msg {
                        MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(t) if is_request(&inb.header, target) => {
                            answers.asked();
                            companion.on_request(t, now)
                        }
                        m => view.update(m, now),
                    }
                }
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => tokio::time::sleep(wake).await,
            },
            _ = tokio::time::sleep(wake) => {}
        }
    }
}

#[cfg(test)]
#[path = "avoidance_tests.rs"]
mod tests;
