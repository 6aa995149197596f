//! The simulator as a library user drives it: one simulation, its clock, its ground truth and its gate,
//! run against PX4 SITL (TCP, lockstep) or a board (serial, wall clock).

use std::net::SocketAddr;
use std::time::Duration;

use tokio::sync::watch;

use crate::cancel::Cancel;
use crate::error::SimError;
use crate::hil::gate::Gate;
use crate::hil::gateway::{Gateway, GatewayConfig};
use crate::hil::lockstep::LockstepConfig;
use crate::hil::serial::{self, WallClockConfig, WallClockReport};
use crate::hil::stepper::Observers;
use crate::hil::tcp::{LockstepReport, SitlServer, run_lockstep};
use crate::sim::{GroundTruth, SimConfig, Simulation};
use crate::time::SimClock;

/// A simulator: the world, and what the host watches.
#[derive(Debug)]
pub struct Simulator {
    sim: Simulation,
    observers: Observers,
}

impl Simulator {
    /// The iris resting at the configured home.
    pub fn new(config: SimConfig) -> Self {
        let sim = Simulation::new(config);
        let (truth, _) = watch::channel(sim.truth());
        Self {
            sim,
            observers: Observers {
                clock: SimClock::default(),
                truth,
                gate: None,
            },
        }
    }

    /// Installs a gate ([`crate::hil::gate`]) the host holds simulated time with.
    pub fn with_gate(mut self, gate: Gate) -> Self {
        self.observers.gate = Some(gate);
        self
    }

    /// The simulated clock (cheap to read from any thread).
    pub fn clock(&self) -> SimClock {
        self.observers.clock.clone()
    }

    /// The ground truth, updated after every step.
    pub fn truth(&self) -> watch::Receiver<GroundTruth> {
        self.observers.truth.subscribe()
    }

    /// The simulation (to inspect or place the vehicle before a run).
    pub fn simulation_mut(&mut self) -> &mut Simulation {
        &mut self.sim
    }

    /// Serves PX4 SITL in lockstep on `server`: waits for it to connect (at most `accept_within`), then
    /// runs until cancelled or the link fails.
    pub async fn run_sitl(
        &mut self,
        server: &SitlServer,
        accept_within: Duration,
        lockstep: &LockstepConfig,
        cancel: &Cancel,
    ) -> Result<LockstepReport, SimError> {
        let Some(stream) = server.accept(accept_within, cancel).await? else {
            return Ok(LockstepReport {
                lockstep: Default::default(),
                steps: Default::default(),
                sim_s: 0.0,
                wall_s: 0.0,
            });
        };
        let (report, result) = run_lockstep(stream, &mut self.sim, &mut self.observers, lockstep, cancel).await;
        result.map(|()| report)
    }

    /// Like [`Self::run_sitl`], binding `addr` first.
    pub async fn serve_sitl(
        &mut self,
        addr: SocketAddr,
        accept_within: Duration,
        lockstep: &LockstepConfig,
        cancel: &Cancel,
    ) -> Result<LockstepReport, SimError> {
        let server = SitlServer::bind(addr).await?;
        self.run_sitl(&server, accept_within, lockstep, cancel).await
    }

    /// Runs a board on serial `device` at `baud` on the wall clock, with its gateway if given, until
    /// cancelled or the link fails.
    pub async fn run_hitl(
        &mut self,
        device: &str,
        baud: u32,
        gateway: Option<GatewayConfig>,
        config: &WallClockConfig,
        cancel: &Cancel,
    ) -> Result<WallClockReport, SimError> {
        let port = serial::open(device, baud)?;
        let gateway = match gateway {
            Some(g) => Some(Gateway::open(g).await?),
            None => None,
        };
        self.run_on_port(port, gateway, config, cancel).await
    }

    /// Runs the wall-clock loop on any byte stream (a serial port, a pty, a test's duplex pipe).
    pub async fn run_on_port<P>(
        &mut self,
        port: P,
        gateway: Option<Gateway>,
        config: &WallClockConfig,
        cancel: &Cancel,
    ) -> Result<WallClockReport, SimError>
    where
        P: tokio::io::AsyncRead + tokio::io::AsyncWrite + Send + 'static,
    {
        let (report, result) =
            serial::run_wall_clock(port, &mut self.sim, &mut self.observers, gateway, config, cancel).await;
        result.map(|()| report)
    }
}
