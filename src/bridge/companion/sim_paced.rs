//! The avoidance companion on simulated time ([`super::pacing::Pacing::SimulatedTime`]): prgenuav's
//! simulator, in this process, holds PX4's clock at every answer period (its gate) until the companion has
//! answered PX4's latest request with a plan made from the vehicle's true pose at that instant, then lets
//! time go on. A loaded machine only slows the flight down: no answer is late, none mirrors PX4's setpoint
//! for want of a plan, and the virtual camera sees the boxes from where the vehicle is at that instant.
#![allow(deprecated)] // TRAJECTORY_REPRESENTATION_WAYPOINTS: deprecated upstream since PX4 1.15 removed it.

use std::sync::Arc;
use std::time::{Duration, Instant};

use mavlink::dialects::common::MavMessage;
use simulator::{GroundTruth, STEP, SimTime};
use tokio::sync::broadcast::{self, error::TryRecvError};

use super::avoidance::{Answers, Companion, CompanionStats, REQUEST_STALE, is_request};
use super::frame::TestFrame;
use super::steer::Steer;
use super::steer_worker::SteerWorker;
use crate::bridge::hil::gate::SimGate;
use crate::bridge::wire::clock::VehicleClock;
use crate::bridge::wire::exchange::Target;
use crate::bridge::wire::link::{Inbound, Link};
use crate::bridge::wire::pose::PoseNed;
use crate::bridge::wire::vehicle::VehicleView;
use crate::model::{GeoPoint, LocalProjection};

/// What the companion paces itself on.
#[derive(Debug, Clone, PartialEq)]
pub struct SimPaced {
    /// The in-process simulator's gate.
    pub gate: SimGate,
    /// PX4's local frame in the test's frame (`None`: they coincide).
    pub frame: Option<TestFrame>,
    /// The test's home: the origin of the test's frame (the simulator's truth is projected about it).
    pub test_home: GeoPoint,
    /// Simulated time between answers (10 Hz, as PX4-Avoidance).
    pub period: Duration,
}

/// PX4 v1.12-v1.15 stream TRAJECTORY_REPRESENTATION_WAYPOINTS at 5 Hz on the onboard link
/// (`mavlink_main.cpp`, MAVLINK_MODE_ONBOARD): the interval assumed before two requests were seen.
const REQUEST_INTERVAL: Duration = Duration::from_millis(200);
/// A request is overdue this long (PX4 time) after the interval: the stream's own jitter is a step or two.
const REQUEST_SLACK: Duration = Duration::from_millis(20);
/// The longest wall wait at a hold for overdue requests (sent by PX4, not yet through the UDP link).
const OVERDUE_WAIT: Duration = Duration::from_millis(50);
/// The longest wall wait at a hold for a session's turn (its sends take microseconds).
const TURN_WAIT: Duration = Duration::from_millis(200);
/// Wall time PX4's MAVLink receiver is given to take the answer before simulated time goes on, so the
/// answer lands at the instant it was planned for on an idle machine.
const SETTLE: Duration = Duration::from_micros(2000);

/// The companion's view between holds: the vehicle, PX4's requests and when the last two were sent.
struct State {
    view: VehicleView,
    companion: Companion,
    /// PX4 time of the last request and the interval before it.
    last_request: Option<(Duration, Duration)>,
}

/// Runs the answers until the simulator stops (its gate closes) or the steering is lost.
pub(super) async fn run(
    link: Arc<Link>,
    target: Target,
    steer: Box<dyn Steer>,
    stats: Arc<CompanionStats>,
    paced: SimPaced,
) {
    let Some(mut holds) = paced.gate.take() else { return };
    let clock = link.clock();
    let mut rx = link.subscribe();
    let mut st = State {
        view: VehicleView::default(),
        companion: Companion::default(),
        last_request: None,
    };
    let mut worker = SteerWorker::new(steer);
    let mut answers = Answers::new(link.clone(), stats);
    let project = LocalProjection::new(paced.test_home);
    holds.hold_at(next_instant(paced.gate.clock().now(), paced.period));
    while let Some(hold) = holds.next_hold().await {
        // The next instant first: whatever happens below, the gate holds again one period on.
        holds.hold_at(hold.at.plus(paced.period));
        let now = Duration::from_micros(hold.truth.time.as_micros());
        drain(&mut rx, &mut st, target, &clock, &mut answers);
        if st.overdue(now) {
            wait_for_request(&mut rx, &mut st, now, target, &clock, &mut answers).await;
        }
        st.view.pose = Some(truth_pose(&hold.truth, &project, paced.frame));
        let planned = match st.companion.steer_input(&st.view, now) {
            Some(input) => match worker.compute(input, now).await {
                Some(out) => out,
                None => return,
            },
            None => None,
        };
        let usec = hold.truth.time.as_micros();
        answers.send(&mut st.companion, &mut worker, planned, now, usec).await;
        paced.gate.serve_turns(hold.at, TURN_WAIT).await;
        settle().await;
        hold.release();
    }
}

impl State {
    /// Takes one message from the vehicle.
    fn take(&mut self, inb: &Inbound, target: Target, clock: &VehicleClock, answers: &mut Answers) {
        match &inb.msg {
            MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(t) if is_request(&inb.header, target) => {
                answers.asked();
                // PX4's clock is the simulator's in lockstep: the request's own stamp is its instant.
                let at = Duration::from_micros(t.time_usec);
                let interval = self
                    .last_request
                    .map_or(REQUEST_INTERVAL, |(last, _)| at.saturating_sub(last));
                self.last_request = Some((at, interval.max(STEP)));
                self.companion.on_request(t, at);
            }
            m => self.view.update(m, clock.now()),
        }
    }

    /// PX4 is asking, and its next request was due before `now` but has not come through yet.
    fn overdue(&self, now: Duration) -> bool {
        self.last_request.is_some_and(|(last, interval)| {
            let age = now.saturating_sub(last);
            age > interval + REQUEST_SLACK && age < REQUEST_STALE
        })
    }
}

/// Everything the link has delivered so far, without waiting.
fn drain(
    rx: &mut broadcast::Receiver<Arc<Inbound>>,
    st: &mut State,
    target: Target,
    clock: &VehicleClock,
    answers: &mut Answers,
) {
    loop {
        match rx.try_recv() {
            Ok(inb) => st.take(&inb, target, clock, answers),
            Err(TryRecvError::Lagged(_)) => {}
            Err(TryRecvError::Empty | TryRecvError::Closed) => return,
        }
    }
}

/// Waits (at most [`OVERDUE_WAIT`] of wall time) until the newest request is no longer overdue at `now`,
/// taking what arrives meanwhile.
async fn wait_for_request(
    rx: &mut broadcast::Receiver<Arc<Inbound>>,
    st: &mut State,
    now: Duration,
    target: Target,
    clock: &VehicleClock,
    answers: &mut Answers,
) {
    let deadline = Instant::now() + OVERDUE_WAIT;
    while st.overdue(now) {
        match tokio::time::timeout_at(deadline.into(), rx.recv()).await {
            Ok(Ok(inb)) => st.take(&inb, target, clock, answers),
            Ok(Err(broadcast::error::RecvError::Lagged(_))) => {}
            Ok(Err(broadcast::error::RecvError::Closed)) | Err(_) => return,
        }
    }
}

/// Gives PX4's receiver thread a moment (a blocking sleep: tokio's timers are millisecond-grained).
async fn settle() {
    let _ = tokio::task::spawn_blocking(|| std::thread::sleep(SETTLE)).await;
}

/// The first instant on the `period` grid after `now`: holds fall on the same instants in every flight.
fn next_instant(now: SimTime, period: Duration) -> SimTime {
    let p = period.as_micros().max(1) as u64;
    SimTime::from_micros((now.as_micros() / p + 1) * p)
}

/// The simulator's truth as PX4 reports a pose: in PX4's local frame (`frame` maps the test's frame to it),
/// heights above the ground the vehicle started on, yaw clockwise from North.
fn truth_pose(t: &GroundTruth, test_home: &LocalProjection, frame: Option<TestFrame>) -> PoseNed {
    let (n, e) = test_home.project(t.position.lat_deg, t.position.lon_deg);
    let test = [n, e, t.position_ned_m.z];
    let (_, _, yaw) = t.attitude.euler_angles();
    let v = t.velocity_ned_m_s;
    PoseNed {
        time_boot_ms: u32::try_from(t.time.as_micros() / 1000).unwrap_or(u32::MAX),
        pos_ned: frame.map_or(test, |f| f.to_vehicle(test)),
        vel_ned: [v.x, v.y, v.z],
        yaw_rad: Some(yaw),
    }
}

#[cfg(test)]
#[path = "sim_paced_tests.rs"]
mod tests;
