//! prgenuav's iris simulator running beside one flight, on the flight's runtime: bound before PX4 starts (a
//! taken port is said at once, naming it), served until the flight ends, then stopped and awaited (bounded)
//! so its port is free for the next flight. A simulator that loses PX4 ends by itself and says why
//! ([`SimRun::failure`]).

use std::net::SocketAddr;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use serde::Serialize;
use simulator::hil::gate::{GateConfig, gate};
use simulator::hil::gateway::{Gateway, GatewayConfig};
use simulator::hil::lockstep::LockstepConfig;
use simulator::hil::serial::{self, WallClockConfig};
use simulator::hil::tcp::{SitlServer, port_of_instance};
use simulator::{Cancel, SimConfig, SimError, Simulator};
use tokio::task::JoinHandle;

use super::gate::SimGate;

/// The longest the simulator holds simulated time for the companion (wall time): far beyond any plan, short
/// of the bridge's lost-link silence, so a companion that hangs costs a late release, not the flight.
pub const MAX_HOLD: Duration = Duration::from_secs(2);
/// How long a stopped simulator may take to end (a hold in progress ends within [`MAX_HOLD`]).
const STOP_WAIT: Duration = Duration::from_secs(5);

/// What the simulator did in one flight, for the flight's log and `fly --json`.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SimSummary {
    /// `tcp lockstep` or `serial wall clock`.
    pub link: &'static str,
    /// The seed of its sensor noise (and gusts).
    pub seed: u64,
    /// Simulated seconds run.
    pub sim_s: f64,
    /// Wall seconds run.
    pub wall_s: f64,
    /// Physics steps of 4 ms.
    pub steps: u64,
    /// Motor commands from PX4.
    pub answers: u64,
    /// Lockstep steps taken because PX4's answer did not come within the wait (100 ms).
    pub actuator_timeouts: u64,
    /// Holds of simulated time for the companion, released in time.
    pub holds: u64,
    /// Holds released late (after [`MAX_HOLD`]) or never.
    pub late_releases: u64,
    /// Simulated time PX4 first armed the motors at, seconds.
    pub armed_at_s: Option<f64>,
    /// Why it ended on its own (PX4 lost, the device gone), if it did.
    pub error: Option<String>,
}

impl SimSummary {
    /// Simulated seconds per wall second.
    pub fn real_time_factor(&self) -> f64 {
        if self.wall_s > 0.0 {
            self.sim_s / self.wall_s
        } else {
            0.0
        }
    }
}

impl std::fmt::Display for SimSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "simulator ({}, seed {}): {:.1} s simulated in {:.1} s (x{:.2}), {} steps, {} motor commands, {} \
             waits timed out, {} holds, {} released late",
            self.link,
            self.seed,
            self.sim_s,
            self.wall_s,
            self.real_time_factor(),
            self.steps,
            self.answers,
            self.actuator_timeouts,
            self.holds,
            self.late_releases
        )?;
        if let Some(t) = self.armed_at_s {
            write!(f, ", armed at {t:.3} s")?;
        }
        match &self.error {
            Some(e) => write!(f, "; ended: {e}"),
            None => Ok(()),
        }
    }
}

/// A simulator serving one flight; cancelled (and its task aborted) when dropped.
pub struct SimRun {
    cancel: Cancel,
    task: Option<JoinHandle<()>>,
    ended: Arc<Mutex<Option<SimSummary>>>,
}

impl SimRun {
    /// Binds TCP `127.0.0.1:4560+instance` and serves PX4 SITL in lockstep there until stopped; with `paced`
    /// the companion holds simulated time through the returned gate. PX4 must connect within `accept_within`.
    pub async fn serve_tcp(
        instance: u8,
        config: SimConfig,
        lockstep: LockstepConfig,
        paced: bool,
        accept_within: Duration,
    ) -> Result<(SimRun, Option<SimGate>), SimError> {
        let addr = SocketAddr::from(([127, 0, 0, 1], port_of_instance(u16::from(instance))));
        let server = SitlServer::bind(addr).await?;
        let mut sim = Simulator::new(config);
        let mut paced_gate = None;
        if paced {
            let (g, handle) = gate(GateConfig {
                period: None,
                max_hold: MAX_HOLD,
            });
            paced_gate = Some(SimGate::new(handle, sim.clock(), config.home));
            sim = sim.with_gate(g);
        }
        let seed = config.seed;
        let armed = first_armed(&sim);
        let run = Self::spawn(move |cancel| async move {
            let r = sim.run_sitl(&server, accept_within, &lockstep, &cancel).await;
            let mut s = SimSummary {
                link: "tcp lockstep",
                seed,
                armed_at_s: armed.borrow().map(|t| t.as_secs_f64()),
                ..SimSummary::default()
            };
            match r {
                Ok(r) => {
                    (s.sim_s, s.wall_s, s.steps) = (r.sim_s, r.wall_s, r.lockstep.steps);
                    (s.answers, s.actuator_timeouts) = (r.lockstep.answers, r.lockstep.timeouts);
                    (s.holds, s.late_releases) = (r.steps.holds, r.steps.late_releases);
                }
                Err(e) => s.error = Some(e.to_string()),
            }
            s
        });
        Ok((run, paced_gate))
    }

    /// Opens serial `device` (a board, or a pty to PX4 SITL) and runs the simulator on the wall clock there
    /// until stopped, with the board's other traffic through `gateway` if given.
    pub async fn serve_serial(
        device: &str,
        baud: u32,
        config: SimConfig,
        gateway: Option<GatewayConfig>,
    ) -> Result<SimRun, SimError> {
        let port = serial::open(device, baud)?;
        let gateway = match gateway {
            Some(g) => Some(Gateway::open(g).await?),
            None => None,
        };
        let mut sim = Simulator::new(config);
        let seed = config.seed;
        Ok(Self::spawn(move |cancel| async move {
            let r = sim
                .run_on_port(port, gateway, &WallClockConfig::default(), &cancel)
                .await;
            let mut s = SimSummary {
                link: "serial wall clock",
                seed,
                ..SimSummary::default()
            };
            match r {
                Ok(r) => {
                    (s.wall_s, s.steps, s.answers) = (r.wall_s, r.steps, r.answers);
                    s.sim_s = r.steps as f64 * simulator::STEP.as_secs_f64();
                }
                Err(e) => s.error = Some(e.to_string()),
            }
            s
        }))
    }

    /// Starts `body` (the simulator's run, ending with its summary) on the runtime.
    fn spawn<F, Fut>(body: F) -> SimRun
    where
        F: FnOnce(Cancel) -> Fut,
        Fut: std::future::Future<Output = SimSummary> + Send + 'static,
    {
        let cancel = Cancel::new();
        let ended = Arc::new(Mutex::new(None));
        let keep = ended.clone();
        let fut = body(cancel.clone());
        let task = tokio::spawn(async move {
            let summary = fut.await;
            *keep.lock().unwrap_or_else(PoisonError::into_inner) = Some(summary);
        });
        SimRun {
            cancel,
            task: Some(task),
            ended,
        }
    }

    /// Why the simulator ended on its own, if it has (PX4 closed the link, the device vanished).
    pub fn failure(&self) -> Option<String> {
        let ended = self.ended.lock().unwrap_or_else(PoisonError::into_inner);
        ended.as_ref().and_then(|s| s.error.clone())
    }

    /// Stops the simulator and waits (bounded) until it has let go of its port or device.
    pub async fn stop(mut self) -> SimSummary {
        self.cancel.cancel();
        if let Some(task) = self.task.take() {
            let abort = task.abort_handle();
            if tokio::time::timeout(STOP_WAIT, task).await.is_err() {
                abort.abort();
            }
        }
        let ended = self.ended.lock().unwrap_or_else(PoisonError::into_inner).take();
        ended.unwrap_or_else(|| SimSummary {
            error: Some(format!("did not stop within {STOP_WAIT:?}")),
            ..SimSummary::default()
        })
    }
}

/// A watch of the simulated time the motors were first armed at (for the summary: a flight's start on
/// simulated time).
fn first_armed(sim: &Simulator) -> tokio::sync::watch::Receiver<Option<simulator::SimTime>> {
    let mut truth = sim.truth();
    let (tx, rx) = tokio::sync::watch::channel(None);
    tokio::spawn(async move {
        while truth.changed().await.is_ok() {
            let t = *truth.borrow_and_update();
            if t.armed {
                tx.send_replace(Some(t.time));
                return;
            }
        }
    });
    rx
}

impl Drop for SimRun {
    fn drop(&mut self) {
        self.cancel.cancel();
        if let Some(task) = self.task.take() {
            task.abort();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn a_taken_port_is_refused_naming_it_and_a_stopped_simulator_frees_its_port() {
        // Instance 9's port, unlikely to be served during tests; taken here first.
        let port = port_of_instance(9);
        let Ok(squatter) = std::net::TcpListener::bind(("127.0.0.1", port)) else {
            return; // someone serves it already: nothing to learn here
        };
        let lockstep = LockstepConfig::default();
        let wait = Duration::from_secs(30);
        let e = match SimRun::serve_tcp(9, SimConfig::default(), lockstep, false, wait).await {
            Err(e) => e.to_string(),
            Ok(_) => panic!("the port is taken"),
        };
        assert!(
            e.contains(&format!("TCP port {port} is in use")) && e.contains("stop it"),
            "{e}"
        );
        drop(squatter);
        let (run, gate) = SimRun::serve_tcp(9, SimConfig::default(), lockstep, true, wait)
            .await
            .expect("free now");
        assert!(gate.is_some() && run.failure().is_none());
        let s = run.stop().await;
        assert_eq!((s.link, s.steps, s.error), ("tcp lockstep", 0, None));
        std::net::TcpListener::bind(("127.0.0.1", port)).expect("the stopped simulator let go of its port");
    }
}
