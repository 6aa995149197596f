//! How the avoidance companion paces its answers, and the task that runs them: free-running as
//! PX4-Avoidance ([`super::avoidance`]), against a vehicle that holds its clock (the mock's lockstep), or on
//! the in-process simulator's time ([`super::sim_paced`]).

use std::sync::Arc;
use std::time::Duration;

use tokio::task::JoinHandle;

use super::avoidance::{self, CompanionStats};
use super::sim_paced;
pub use super::sim_paced::SimPaced;
use super::steer::Steer;
use crate::bridge::wire::exchange::Target;
use crate::bridge::wire::link::Link;

/// How the companion paces its answers.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Pacing {
    /// As PX4-Avoidance: answer at 10 Hz (vehicle time) with the latest finished plan.
    #[default]
    FreeRunning,
    /// Answer every request at once, timed by the request's own timestamp (for a vehicle that holds its clock
    /// until the answer: the mock's lockstep), with a plan made from the pose `latency` before the request:
    /// a real companion plans on a camera frame and a pose that are already old when the answer lands.
    Lockstep {
        /// Age of the pose each plan is made from (vehicle time; 20 ms resolution at PX4's 50 Hz stream).
        latency: Duration,
    },
    /// Answer on simulated time: prgenuav's simulator, in this process, holds PX4's clock at every answer
    /// period until the answer to PX4's latest request, planned on the true pose of that instant, is sent
    /// ([`super::sim_paced`]): however loaded the machine, no answer is late.
    SimulatedTime(SimPaced),
}

/// Runs the companion's answers until aborted: a task that reads requests and answers them (see [`Pacing`]),
/// counting its answers in `stats`.
pub fn spawn(
    link: Arc<Link>,
    target: Target,
    steer: Box<dyn Steer>,
    stats: Arc<CompanionStats>,
    pacing: Pacing,
) -> JoinHandle<()> {
    match pacing {
        Pacing::FreeRunning => tokio::spawn(avoidance::run(link, target, steer, stats)),
        Pacing::Lockstep { latency } => tokio::spawn(avoidance::run_lockstep(link, target, steer, stats, latency)),
        Pacing::SimulatedTime(paced) => tokio::spawn(sim_paced::run(link, target, steer, stats, paced)),
    }
}
