//! Runs a `Vehicle` on a transport in a tokio task: pacing, fault injection, start and stop.
//!
//! `MockAutopilot::builder()...spawn().await` returns a `MockHandle` that knows the bound
//! address and stops the task on `shutdown()` or drop.

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::time::{Duration, Instant};

use mavlink::MavHeader;
use mavlink::dialects::common::{MavMessage, MavMissionResult};
use tokio::sync::{mpsc, watch};
use tokio::task::JoinHandle;

use crate::clock::{Pacer, SpeedFactor};
use crate::link::{FaultError, Faults, FaultyLink, REBOOT_DOWNTIME};
use crate::params::ParamValue;
use crate::transport::{MavConnTransport, Transport, UdpTransport};
use crate::vehicle::{CollisionWorld, Vehicle, VehicleConfig, VehicleState};

/// Default fixed physics step (250 Hz, PX4's rate-controller order of magnitude).
pub const DEFAULT_STEP: Duration = Duration::from_millis(4);
/// At most this many steps run between two looks at the network.
const MAX_BATCH: u32 = 250;
/// After a lockstep wait, at most this much simulated time runs unpaced to catch up with the speed factor.
const LOCKSTEP_MAX_LAG: Duration = Duration::from_secs(1);
/// Default wall-time bound of one lockstep wait for the companion's answer.
pub const DEFAULT_LOCKSTEP_WAIT: Duration = Duration::from_secs(2);

/// Where the mock talks.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkSpec {
    /// As PX4 SITL instance N: bind 127.0.0.1:14580+N, send to 127.0.0.1:14540+N (N > 9: 14549).
    Px4Sitl {
        /// Instance number.
        instance: u16,
    },
    /// Bind `addr` (port 0 for an ephemeral port) and answer whoever talks first.
    UdpIn(SocketAddr),
    /// Bind `bind` and send to `remote` (the remote follows the last sender).
    UdpOut {
        /// Local address.
        bind: SocketAddr,
        /// Peer address.
        remote: SocketAddr,
    },
    /// Any rust-mavlink address (`tcpin:...`, `serial:...`, `udpin:...`).
    Address(String),
}

impl LinkSpec {
    /// Local and remote UDP addresses of PX4 SITL instance `n`.
    pub fn px4_ports(instance: u16) -> (SocketAddr, SocketAddr) {
        let lo = IpAddr::V4(Ipv4Addr::LOCALHOST);
        let remote = 14540 + instance.min(9);
        (
            SocketAddr::new(lo, 14580u16.saturating_add(instance)),
            SocketAddr::new(lo, remote),
        )
    }
}

/// Why the mock could not start.
#[derive(Debug, thiserror::Error)]
pub enum MockError {
    /// Binding or connecting failed.
    #[error("cannot open link {link}: {source}")]
    Link {
        /// The link that failed.
        link: String,
        /// The IO error.
        source: std::io::Error,
    },
    /// Invalid fault settings.
    #[error(transparent)]
    Faults(#[from] FaultError),
    /// The runner task panicked or was cancelled.
    #[error("mock autopilot task failed: {0}")]
    Task(String),
}

/// Entry point of the builder.
pub struct MockAutopilot;

impl MockAutopilot {
    /// A builder with PX4 SITL instance 0's link, real time and no faults.
    pub fn builder() -> Builder {
        Builder {
            link: LinkSpec::Px4Sitl { instance: 0 },
            speed: SpeedFactor::default(),
            step: DEFAULT_STEP,
            faults: Faults::default(),
            vehicle: VehicleConfig {
                estimator_settle: crate::preflight::DEFAULT_ESTIMATOR_SETTLE,
                ..VehicleConfig::default()
            },
            lockstep: None,
        }
    }
}

/// Configures and starts a mock autopilot.
pub struct Builder {
    link: LinkSpec,
    speed: SpeedFactor,
    step: Duration,
    faults: Faults,
    vehicle: VehicleConfig,
    lockstep: Option<Duration>,
}

impl Builder {
    /// Lockstep with the avoidance companion: while flying with COM_OBS_AVOID = 1, simulated time stands
    /// still after each trajectory request until the companion answers (at most `wait` of wall time, then
    /// it goes on as PX4 would). The speed factor becomes an upper bound, and a flight no longer depends on
    /// how fast the companion's CPU is. `None` (the default): free-running, as PX4 on real hardware.
    /// Meant for fault-free links: injected latency is counted in simulated time, which stands still, so
    /// every answer would wait out the wall-time bound.
    pub fn lockstep(mut self, wait: Option<Duration>) -> Self {
        self.lockstep = wait;
        self
    }

    /// Where to talk.
    pub fn link(mut self, link: LinkSpec) -> Self {
        self.link = link;
        self
    }

    /// Simulated time runs this much faster than wall time.
    pub fn speed_factor(mut self, speed: SpeedFactor) -> Self {
        self.speed = speed;
        self
    }

    /// Fixed physics step (default 4 ms).
    pub fn step(mut self, step: Duration) -> Self {
        self.step = step.max(Duration::from_micros(100));
        self
    }

    /// Link faults.
    pub fn faults(mut self, faults: Faults) -> Self {
        self.faults = faults;
        self
    }

    /// Answer every mission upload with this MISSION_ACK code.
    pub fn reject_mission(mut self, code: Option<MavMissionResult>) -> Self {
        self.vehicle.reject_mission = code;
        self
    }

    /// Refuse every arming attempt.
    pub fn fail_arm(mut self, fail: bool) -> Self {
        self.vehicle.fail_arm = fail;
        self
    }

    /// Act as this PX4 release (AUTOPILOT_VERSION; no `COM_OBS_AVOID` from v1.16).
    pub fn px4_release(mut self, release: crate::release::Px4Release) -> Self {
        self.vehicle.release = release;
        self
    }

    /// Crash (disarm, STATUSTEXT, on ground) when entering an obstacle.
    pub fn collision(mut self, world: Box<dyn CollisionWorld>) -> Self {
        self.vehicle.collision = Some(world);
        self
    }

    /// Vehicle time after boot until arming, GPS fix and home are possible (default
    /// [`crate::preflight::DEFAULT_ESTIMATOR_SETTLE`]; zero: ready at once).
    pub fn estimator_settle(mut self, settle: Duration) -> Self {
        self.vehicle.estimator_settle = settle;
        self
    }

    /// Set a parameter at boot.
    pub fn param(mut self, name: &str, value: ParamValue) -> Self {
        self.vehicle.params.push((name.to_string(), value));
        self
    }

    /// The kinematic model's constants (a profile fitted to some reference; default: the original model).
    pub fn tuning(mut self, tuning: crate::dynamics::Tuning) -> Self {
        self.vehicle.tuning = tuning;
        self
    }

    /// Seed of the gusts (the tuning's `MOCK_GUST_ACC`): the same seed flies the same gusts, flight by
    /// flight since the vehicle started.
    pub fn seed(mut self, seed: u64) -> Self {
        self.vehicle.seed = seed;
        self
    }

    /// Boot (and keep the EKF origin) at `home`.
    pub fn home(mut self, home: geodesy::GeoPoint) -> Self {
        self.vehicle.home = home;
        self
    }

    /// Replace the whole vehicle configuration.
    pub fn vehicle(mut self, cfg: VehicleConfig) -> Self {
        self.vehicle = cfg;
        self
    }

    /// Open the link and start the simulation task (needs a tokio runtime).
    pub async fn spawn(self) -> Result<MockHandle, MockError> {
        self.faults.validate()?;
        let link_err = |link: &LinkSpec, source| MockError::Link {
            link: format!("{link:?}"),
            source,
        };
        let (local, remote) = match &self.link {
            LinkSpec::Px4Sitl { instance } => {
                let (l, r) = LinkSpec::px4_ports(*instance);
                (Some(l), Some(r))
            }
            LinkSpec::UdpIn(a) => (Some(*a), None),
            LinkSpec::UdpOut { bind, remote } => (Some(*bind), Some(*remote)),
            LinkSpec::Address(_) => (None, None),
        };
        let vehicle = Vehicle::new(self.vehicle);
        let (stop_tx, stop_rx) = watch::channel(false);
        let (state_tx, state_rx) = watch::channel(vehicle.state());
        let runner = Runner {
            vehicle,
            link: FaultyLink::new(self.faults),
            step: self.step,
            speed: self.speed,
            lockstep: self.lockstep,
        };
        let (task, local_addr) = match (&self.link, local) {
            (LinkSpec::Address(addr), _) => {
                let t = MavConnTransport::connect(addr)
                    .await
                    .map_err(|e| link_err(&self.link, e))?;
                (tokio::spawn(runner.run(t, stop_rx, state_tx)), None)
            }
            (_, Some(l)) => {
                let t = UdpTransport::bind(l, remote)
                    .await
                    .map_err(|e| link_err(&self.link, e))?;
                let bound = t.local_addr().map_err(|e| link_err(&self.link, e))?;
                (tokio::spawn(runner.run(t, stop_rx, state_tx)), Some(bound))
            }
            (_, None) => unreachable!("every UDP link spec has a local address"),
        };
        Ok(MockHandle {
            local_addr,
            stop: stop_tx,
            state: state_rx,
            task: Some(task),
        })
    }
}

/// A running mock autopilot; dropping it stops the task.
pub struct MockHandle {
    local_addr: Option<SocketAddr>,
    stop: watch::Sender<bool>,
    state: watch::Receiver<VehicleState>,
    task: Option<JoinHandle<()>>,
}

impl MockHandle {
    /// The bound UDP address (None for rust-mavlink address links).
    pub fn local_addr(&self) -> Option<SocketAddr> {
        self.local_addr
    }

    /// The latest vehicle state.
    pub fn state(&self) -> VehicleState {
        *self.state.borrow()
    }

    /// A receiver of vehicle states (updated after every batch of steps).
    pub fn watch_state(&self) -> watch::Receiver<VehicleState> {
        self.state.clone()
    }

    /// Stop the task and wait for it (bounded: 5 s).
    pub async fn shutdown(mut self) -> Result<(), MockError> {
        let _ = self.stop.send(true);
        let Some(task) = self.task.take() else {
            return Ok(());
        };
        match tokio::time::timeout(Duration::from_secs(5), task).await {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(MockError::Task(e.to_string())),
            Err(_) => Err(MockError::Task("did not stop within 5 s".into())),
        }
    }
}

impl Drop for MockHandle {
    fn drop(&mut self) {
        let _ = self.stop.send(true);
        if let Some(t) = self.task.take() {
            t.abort();
        }
    }
}

struct Runner {
    vehicle: Vehicle,
    link: FaultyLink,
    step: Duration,
    speed: SpeedFactor,
    lockstep: Option<Duration>,
}

/// Reads the transport in its own task, so the simulation loop polls a channel instead of blocking on the socket.
fn spawn_receiver<T: Transport>(
    transport: std::sync::Arc<T>,
) -> (JoinHandle<()>, mpsc::Receiver<(MavHeader, MavMessage)>) {
    let (in_tx, in_rx) = mpsc::channel::<(MavHeader, MavMessage)>(1024);
    let receiver = tokio::spawn(async move {
        loop {
            match transport.recv().await {
                Ok(msgs) => {
                    for m in msgs {
                        if in_tx.send(m).await.is_err() {
                            return;
                        }
                    }
                }
                // ICMP errors, TCP peer gone: back off instead of spinning.
                Err(_) => tokio::time::sleep(Duration::from_millis(20)).await,
            }
        }
    });
    (receiver, in_rx)
}

/// What ended a lockstep wait.
enum Waited {
    Answered,
    TimedOut,
    Stop,
}

impl Runner {
    async fn run<T: Transport>(
        mut self,
        transport: T,
        mut stop: watch::Receiver<bool>,
        state: watch::Sender<VehicleState>,
    ) {
        let transport = std::sync::Arc::new(transport);
        let (receiver, mut in_rx) = spawn_receiver(transport.clone());
        let mut pacer = Pacer::new(self.speed, self.step, Instant::now());
        let mut reboot_pending = self.link.faults().reboot_after;
        loop {
            if *stop.borrow() {
                break;
            }
            while let Ok((h, m)) = in_rx.try_recv() {
                self.link.incoming(self.vehicle.now(), h, m);
            }
            self.deliver(&*transport).await;
            if let Some(wait) = self.lockstep
                && self.vehicle.lockstep_blocked()
            {
                state.send_replace(self.vehicle.state());
                match self.wait_for_answer(&*transport, &mut in_rx, &mut stop, wait).await {
                    Waited::Stop => break,
                    Waited::TimedOut => self.vehicle.lockstep_release(),
                    Waited::Answered => {}
                }
                pacer.limit_lag(self.vehicle.now(), Instant::now(), LOCKSTEP_MAX_LAG);
                continue;
            }
            let target = pacer.sim_target(Instant::now());
            self.run_batch(&*transport, target, &mut reboot_pending).await;
            state.send_replace(self.vehicle.state());
            if self.lockstep.is_some() && self.vehicle.lockstep_blocked() {
                continue;
            }
            if target.is_none() {
                tokio::task::yield_now().await;
                continue;
            }
            let next_sim = self.vehicle.now() + self.step;
            let wake = pacer.wall_due(next_sim).unwrap_or_else(Instant::now);
            tokio::select! {
                _ = stop.changed() => {}
                m = in_rx.recv() => match m {
                    Some((h, m)) => self.link.incoming(self.vehicle.now(), h, m),
                    None => break,
                },
                _ = tokio::time::sleep_until(wake.into()) => {}
            }
        }
        receiver.abort();
    }

    /// Runs up to [`MAX_BATCH`] steps, as far as the pacer's `target` (`None`: unpaced) allows and until a
    /// lockstep wait, rebooting the vehicle when the fault is due.
    async fn run_batch<T: Transport>(
        &mut self,
        transport: &T,
        target: Option<Duration>,
        reboot_pending: &mut Option<Duration>,
    ) {
        let mut n = 0;
        while n < MAX_BATCH
            && target.is_none_or(|t| self.vehicle.now() + self.step <= t)
            && !(self.lockstep.is_some() && self.vehicle.lockstep_blocked())
        {
            self.vehicle.step(self.step);
            n += 1;
            if let Some(at) = reboot_pending.filter(|at| self.vehicle.now() >= *at) {
                *reboot_pending = None;
                self.vehicle.reboot();
                self.link.kill_until(at + REBOOT_DOWNTIME);
            }
            self.deliver(transport).await;
        }
    }

    /// Simulated time stands still until the companion answers, the wall-time bound passes or the mock stops.
    async fn wait_for_answer<T: Transport>(
        &mut self,
        transport: &T,
        in_rx: &mut mpsc::Receiver<(MavHeader, MavMessage)>,
        stop: &mut watch::Receiver<bool>,
        wait: Duration,
    ) -> Waited {
        let deadline = tokio::time::Instant::now() + wait;
        while self.vehicle.lockstep_blocked() {
            tokio::select! {
                _ = stop.changed() => return Waited::Stop,
                m = in_rx.recv() => match m {
                    Some((h, m)) => {
                        self.link.incoming(self.vehicle.now(), h, m);
                        self.deliver(transport).await;
                    }
                    None => return Waited::Stop,
                },
                _ = tokio::time::sleep_until(deadline) => return Waited::TimedOut,
            }
        }
        Waited::Answered
    }

    /// Hand due incoming messages to the vehicle and send due outgoing ones.
    async fn deliver<T: Transport>(&mut self, transport: &T) {
        let now = self.vehicle.now();
        while let Some((h, m)) = self.link.pop_incoming(now) {
            self.vehicle.handle(&h, &m);
        }
        for m in self.vehicle.drain_outbox().collect::<Vec<_>>() {
            self.link.outgoing(now, m);
        }
        while let Some(m) = self.link.pop_outgoing(now) {
            // A send error (no route, peer gone) must not stop the vehicle.
            let _ = transport.send(&m).await;
        }
    }
}
