//! What every step of one flight shares: the link, the vehicle as last heard, the test and the options, and
//! why the flight stopped. The steps ([`super::anchor`], [`super::setup`], [`super::ready`], [`super::flight`])
//! are methods and functions on [`Session`]; this module depends on none of them.

use std::sync::Arc;
use std::time::Duration;

use mavlink::dialects::common::{MavCmd, MavResult};
use tokio::sync::broadcast;

use super::placement::VehiclePlacement;
use super::report::Status;
use super::tasks::Tasks;
use crate::bridge::companion::avoidance::CompanionStats;
use crate::bridge::companion::frame::TestFrame;
use crate::bridge::options::FlyOptions;
use crate::bridge::px4_version::Px4Version;
use crate::bridge::wire::cancel::CancelToken;
use crate::bridge::wire::command::AckedCommand;
use crate::bridge::wire::exchange::{ProtocolError, RetryPolicy, Target};
use crate::bridge::wire::link::{Inbound, Link};
use crate::bridge::wire::notices::Messages;
use crate::bridge::wire::param_read::ParamRead;
use crate::bridge::wire::vehicle::VehicleView;
use crate::model::TestCase;

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
    pub companion: Arc<CompanionStats>,
    /// PX4's local frame -> the test's frame, once measured ([`super::anchor`]).
    pub frame: Option<TestFrame>,
    /// Where the vehicle stood against the test's home, once known.
    pub placement: Option<VehiclePlacement>,
    /// The vehicle's STATUSTEXT of severity WARNING or worse, as they arrived.
    pub messages: Messages,
    /// The vehicle's MPC_XY_CRUISE (m/s) the planner uses, once read (avoidance and offboard modes).
    pub mpc_xy_cruise_m_s: Option<f64>,
    /// Readiness timing and the arming budget.
    pub ready: Readiness,
    /// The PX4 release the vehicle reported in AUTOPILOT_VERSION (None: another autopilot, or no answer).
    pub px4_version: Option<Px4Version>,
    /// Who answered.
    pub identity: super::identify::VehicleIdentity,
    /// Vehicle time the companion's heartbeat started at (avoidance mode).
    pub companion_beat_from: Option<Duration>,
}

/// Readiness as timed for the report and the arming budget.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Readiness {
    /// Vehicle seconds waited before the vehicle was ready.
    pub waited_s: Option<f64>,
    /// Arming may be retried until this vehicle time.
    pub deadline: Duration,
    /// Vehicle time the mission upload finished.
    pub mission_uploaded_at: Option<Duration>,
    /// Vehicle time the session began waiting for the vehicle (the placement's wait for home counts too).
    pub started: Option<Duration>,
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
        let c = AckedCommand::new(self.target, cmd, params, RetryPolicy::COMMAND);
        self.link.exchange(c, &self.cancel).await
    }

    /// Waits (bounded by the readiness budget, at least 30 s vehicle time) for HOME_POSITION, asking for it once.
    pub async fn wait_home(&mut self) -> Result<(), Stop> {
        self.drain();
        if self.view.home_known {
            return Ok(());
        }
        let p = [242.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        match self.command(MavCmd::MAV_CMD_REQUEST_MESSAGE, p).await {
            // PX4 denies the request while it has no home yet (its stream has nothing to send); home then
            // comes on its own stream, which the wait below covers.
            Ok(())
            | Err(ProtocolError::CommandRefused {
                result: MavResult::MAV_RESULT_DENIED,
                ..
            }) => {}
            Err(e) => self.warnings.push(format!("requesting HOME_POSITION: {e}")),
        }
        let clock = self.link.clock();
        // Home comes once the estimator has a fix: the readiness budget, not a fixed wait.
        let budget = Duration::from_secs_f64(self.opts.ready_budget_s(clock.scale()).max(30.0));
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

    /// Reads the vehicle's parameter `name` (bounded: 4 tries of 1 s); when it does not answer, `Ok(None)` and a
    /// warning saying what is assumed instead (`otherwise`). Only a cancel stops the flight.
    pub async fn read_param(&mut self, name: &str, otherwise: &str) -> Result<Option<f64>, Stop> {
        let quick = RetryPolicy {
            timeout: Duration::from_secs(1),
            max_retries: 3,
        };
        match self
            .link
            .exchange(ParamRead::new(self.target, name, quick), &self.cancel)
            .await
        {
            Ok(v) => Ok(Some(v)),
            Err(ProtocolError::Cancelled) => Err(Stop::new(Status::Aborted, "cancelled")),
            Err(e) => {
                self.warnings.push(format!("{name} not readable ({e}); {otherwise}"));
                Ok(None)
            }
        }
    }
}
