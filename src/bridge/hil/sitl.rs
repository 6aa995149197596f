//! PX4 SITL flown with prgenuav's iris simulator (`--sim iris`): the simulator is bound and serving before
//! PX4 starts (PX4's start-up blocks until sensor time moves), PX4 starts in its release's
//! external-simulator mode at the test's home, and both stop when the flight ends. Over TCP the two run in
//! lockstep (simulated time is PX4's clock) and the avoidance companion holds that time ([`super::gate`]);
//! over a serial pty (`socat`) the simulator runs on the wall clock, as for a board.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use simulator::hil::lockstep::LockstepConfig;
use simulator::{SimConfig, SimError};
use tokio::runtime::Handle;

use super::gate::SimGate;
use super::pty::{PtyBridge, PtyError};
use super::run::{SimRun, SimSummary};
use crate::bridge::options::{SimLink, VehicleSim};
use crate::bridge::sitl::{Px4Build, Px4Sitl, SitlError, SitlSpec};
use crate::model::GeoPoint;

/// The freewheel before PX4's first motor command runs at the speed factor, at most this (PX4's start-up
/// times out under a flood of sensor time).
pub const FREEWHEEL_MAX: f64 = 10.0;
/// PX4 connects within its boot; the simulator waits this much longer before it gives up on it.
const ACCEPT_SLACK: Duration = Duration::from_secs(30);
/// The pty's nominal baud rate (a pty ignores it; a board's USB port is this fast).
pub const PTY_BAUD: u32 = 921_600;

/// What to start.
#[derive(Debug, Clone)]
pub struct IrisSpec {
    /// The user's build, checked ([`Px4Build::check_sim`]).
    pub build: Px4Build,
    /// PX4 instance number (TCP 4560+i, UDP 14540+i).
    pub instance: u8,
    /// Where the simulator puts the vehicle at rest (the test's home).
    pub home: GeoPoint,
    /// Where its nose points at rest, degrees clockwise from North (Gazebo Classic's spawn: 90, East).
    pub heading_deg: f64,
    /// The simulator's seed (sensor noise): the same seed and commands give the same sensor stream.
    pub seed: u64,
    /// The highest real-time factor in lockstep (like `PX4_SIM_SPEED_FACTOR`).
    pub speed_factor: f64,
    /// TCP in lockstep, or a serial pty on the wall clock.
    pub link: SimLink,
    /// The avoidance companion holds simulated time (TCP only).
    pub paced: bool,
    /// How long PX4's startup script may take.
    pub boot_timeout: Duration,
}

/// Why the pair did not start.
#[derive(Debug, thiserror::Error)]
pub enum IrisError {
    /// The simulator could not be had (its port taken, the pty not opened).
    #[error("prgenuav's simulator: {0}")]
    Sim(#[from] SimError),
    /// The serial link's socat could not be had.
    #[error(transparent)]
    Pty(#[from] PtyError),
    /// PX4 did not boot.
    #[error(transparent)]
    Sitl(#[from] SitlError),
}

/// PX4 SITL and its simulator; both stopped when dropped (PX4 first).
pub struct IrisSitl {
    /// The PX4 instance.
    pub px4: Px4Sitl,
    sim: Option<SimRun>,
    pty: Option<PtyBridge>,
    gate: Option<SimGate>,
    handle: Handle,
}

/// The lockstep figures at `speed_factor`: capped there, freewheeling at it (at most [`FREEWHEEL_MAX`]).
pub fn lockstep_config(speed_factor: f64) -> LockstepConfig {
    LockstepConfig {
        speed_cap: Some(speed_factor),
        freewheel_speed: speed_factor.clamp(1.0, FREEWHEEL_MAX),
        ..LockstepConfig::default()
    }
}

impl IrisSitl {
    /// Starts the simulator on `handle`, then PX4 on this thread (which must outlive it: PX4 dies with the
    /// thread that started it), giving up as soon as `stop` rises. Not from inside the runtime.
    pub fn start(handle: &Handle, spec: &IrisSpec, stop: &AtomicBool) -> Result<IrisSitl, IrisError> {
        let config = SimConfig {
            home: spec.home,
            seed: spec.seed,
            heading_deg: spec.heading_deg,
            ..SimConfig::default()
        };
        let (sim, gate, pty) = match spec.link {
            SimLink::Tcp => {
                let lockstep = lockstep_config(spec.speed_factor);
                let accept = spec.boot_timeout + ACCEPT_SLACK;
                let serve = SimRun::serve_tcp(spec.instance, config, lockstep, spec.paced, accept);
                let (sim, gate) = handle.block_on(serve)?;
                (sim, gate, None)
            }
            SimLink::Serial => {
                let pty = PtyBridge::start(spec.instance, &std::env::temp_dir())?;
                let sim = handle.block_on(SimRun::serve_serial(&pty.device(), PTY_BAUD, config, None))?;
                (sim, None, Some(pty))
            }
        };
        let sitl = SitlSpec {
            boot_timeout: spec.boot_timeout,
            ..SitlSpec::with_sim(&spec.build, spec.instance, spec.speed_factor, VehicleSim::Iris).at(spec.home)
        };
        let px4 = Px4Sitl::start_until(&sitl, stop)?;
        Ok(IrisSitl {
            px4,
            sim: Some(sim),
            pty,
            gate,
            handle: handle.clone(),
        })
    }

    /// The gate the avoidance companion holds simulated time with (TCP, paced).
    pub fn gate(&self) -> Option<SimGate> {
        self.gate.clone()
    }

    /// Why the simulator ended on its own (PX4 lost), if it did.
    pub fn sim_failure(&self) -> Option<String> {
        self.sim.as_ref().and_then(SimRun::failure)
    }

    /// Stops the simulator (and socat), waiting until its port is free; what it did. PX4 stays up (frozen
    /// in lockstep) for its console and logs until this is dropped. Not from inside the runtime.
    pub fn finish(&mut self) -> Option<SimSummary> {
        let summary = self.sim.take().map(|s| self.handle.block_on(s.stop()));
        self.pty.take();
        summary
    }
}
