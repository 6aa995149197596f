//! SITL over TCP in lockstep: the simulator is the server PX4 connects to (port 4560 + instance), and
//! simulated time moves only as the lockstep policy ([`super::lockstep`]) allows.

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use tokio::net::{TcpListener, TcpStream};

use super::link::{LinkEvent, Outbox, spawn_reader};
use super::lockstep::{Decision, Lockstep, LockstepConfig, LockstepStats};
use super::messages::classify;
use super::stepper::{Observers, Stamp, StepCounts, Stepper};
use crate::cancel::Cancel;
use crate::error::SimError;
use crate::sim::Simulation;

/// PX4 instance `n` connects to this port.
pub fn port_of_instance(instance: u16) -> u16 {
    4560 + instance
}

/// A bound TCP server PX4 will connect to.
#[derive(Debug)]
pub struct SitlServer {
    listener: TcpListener,
    addr: SocketAddr,
}

impl SitlServer {
    /// Binds `addr` (e.g. 127.0.0.1:4560; port 0 picks a free one).
    pub async fn bind(addr: SocketAddr) -> Result<Self, SimError> {
        let listener = TcpListener::bind(addr).await.map_err(|e| match e.kind() {
            std::io::ErrorKind::AddrInUse => SimError::PortInUse { port: addr.port() },
            _ => SimError::Listen {
                addr: addr.to_string(),
                source: e,
            },
        })?;
        let addr = listener.local_addr().map_err(|e| SimError::Listen {
            addr: addr.to_string(),
            source: e,
        })?;
        Ok(Self { listener, addr })
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Waits for PX4 (at most `within`, or until cancelled: `Ok(None)`).
    pub async fn accept(&self, within: Duration, cancel: &Cancel) -> Result<Option<TcpStream>, SimError> {
        tokio::select! {
            r = tokio::time::timeout(within, self.listener.accept()) => match r {
                Ok(Ok((stream, _))) => {
                    let _ = stream.set_nodelay(true);
                    Ok(Some(stream))
                }
                Ok(Err(e)) => Err(SimError::Listen { addr: self.addr.to_string(), source: e }),
                Err(_) => Err(SimError::NoConnection { addr: self.addr.to_string(), waited: within }),
            },
            _ = cancel.cancelled() => Ok(None),
        }
    }
}

/// What a lockstep run did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LockstepReport {
    /// Lockstep counters.
    pub lockstep: LockstepStats,
    /// Step counters.
    pub steps: StepCounts,
    /// Simulated seconds run.
    pub sim_s: f64,
    /// Wall seconds run.
    pub wall_s: f64,
}

impl LockstepReport {
    /// Simulated seconds per wall second.
    pub fn real_time_factor(&self) -> f64 {
        if self.wall_s > 0.0 {
            self.sim_s / self.wall_s
        } else {
            0.0
        }
    }
}

/// Runs the lockstep exchange with PX4 on `stream` until cancelled (`Ok`) or the link fails (`Err`); the
/// report covers the run either way.
pub async fn run_lockstep(
    stream: TcpStream,
    sim: &mut Simulation,
    obs: &mut Observers,
    config: &LockstepConfig,
    cancel: &Cancel,
) -> (LockstepReport, Result<(), SimError>) {
    let (read, mut write) = stream.into_split();
    let (mut rx, reader) = spawn_reader(read);
    let started = Instant::now();
    let sim_start = sim.time();
    let mut lock = Lockstep::new(*config, started);
    let mut stepper = Stepper::new(true, 0);
    let mut out = Outbox::default();
    let result = loop {
        if cancel.is_cancelled() {
            break Ok(());
        }
        let now = Instant::now();
        let deadline = match lock.decide(now) {
            Decision::Step { timed_out } => {
                stepper.step(sim, &mut out, obs, Stamp::SimTime).await;
                lock.stepped(Instant::now(), timed_out);
                if let Err(e) = out.flush(&mut write, config.link_lost_after).await {
                    break Err(SimError::LinkLost(e));
                }
                continue;
            }
            Decision::WaitUntil(t) => t,
            Decision::LinkLost => {
                break Err(SimError::LinkLost(format!(
                    "PX4 silent for {:?}",
                    config.link_lost_after
                )));
            }
            Decision::NeverAnswered => break Err(SimError::NeverAnswered(config.first_answer_within)),
        };
        tokio::select! {
            ev = rx.recv() => match ev {
                Some(LinkEvent::Frame(f)) => {
                    let t = Instant::now();
                    lock.on_message(t);
                    if let Some(m) = &f.message
                        && stepper.on_incoming(sim, &classify(m))
                    {
                        lock.on_actuators(t);
                    }
                }
                Some(LinkEvent::Closed(why)) => break Err(SimError::LinkLost(format!("PX4 closed the connection ({why})"))),
                None => break Err(SimError::LinkLost("reader stopped".into())),
            },
            _ = tokio::time::sleep_until(deadline.into()) => {}
            _ = cancel.cancelled() => break Ok(()),
        }
    };
    reader.abort();
    let report = LockstepReport {
        lockstep: lock.stats(),
        steps: stepper.counts(),
        sim_s: sim.time().since(sim_start).as_secs_f64(),
        wall_s: started.elapsed().as_secs_f64(),
    };
    let result = result.map_err(|e| match e {
        SimError::LinkLost(why) => SimError::LinkLost(format!(
            "{why} after {:.1} s simulated, {} steps, {} answers, {} waits timed out",
            report.sim_s, report.lockstep.steps, report.lockstep.answers, report.lockstep.timeouts
        )),
        other => other,
    });
    (report, result)
}
