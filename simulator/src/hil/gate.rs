//! A gate on simulated time for a host in the same process: the simulator holds before simulated time
//! passes given instants (every `period` of simulated time, and any instant the host registers) until the
//! host releases it, so a companion or a virtual camera running on simulated time can compute for
//! exactly the state it was handed while PX4 waits in lockstep.
//!
//! ```
//! # async fn host() {
//! use std::time::Duration;
//! use simulator::hil::gate::{GateConfig, gate};
//! use simulator::SimTime;
//! let (gate, mut handle) = gate(GateConfig { period: Some(Duration::from_millis(100)), ..GateConfig::default() });
//! // hand `gate` to the simulator (`Simulator::with_gate`), keep `handle`:
//! handle.hold_at(SimTime::from_millis(1234));
//! while let Some(hold) = handle.next_hold().await {
//!     let state = hold.truth; // the vehicle at hold.truth.time, the first step at or after hold.at
//!     // ... compute, send MAVLink to PX4 ...
//!     hold.release(); // (dropping it releases too)
//! }
//! # drop(gate); }
//! ```
//!
//! A release later than `max_hold` lets the simulator go on anyway and counts a late release; with no
//! handle left, the gate never holds.

use std::collections::BTreeSet;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::sync::{mpsc, oneshot};

use crate::sim::GroundTruth;
use crate::time::SimTime;

/// When the gate holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GateConfig {
    /// Hold every this much simulated time (at `period`, 2 `period`, ...), or only at registered instants.
    pub period: Option<Duration>,
    /// The longest hold (wall time); the simulator then goes on and counts a late release.
    pub max_hold: Duration,
}

impl Default for GateConfig {
    fn default() -> Self {
        Self {
            period: None,
            max_hold: Duration::from_millis(500),
        }
    }
}

/// The simulator's side of the gate.
#[derive(Debug)]
pub struct Gate {
    config: GateConfig,
    shared: Arc<Shared>,
    to_host: mpsc::Sender<Hold>,
    next_periodic: Option<SimTime>,
}

#[derive(Debug, Default)]
struct Shared {
    instants: Mutex<BTreeSet<SimTime>>,
    late: AtomicU64,
    holds: AtomicU64,
}

/// The host's side of the gate.
#[derive(Debug)]
pub struct GateHandle {
    shared: Arc<Shared>,
    from_sim: mpsc::Receiver<Hold>,
}

/// The simulator held at an instant; release it (or drop this) to let simulated time go on.
#[derive(Debug)]
pub struct Hold {
    /// The instant that made it hold.
    pub at: SimTime,
    /// The vehicle's true state at the hold (its `time` is the first step end at or after `at`).
    pub truth: GroundTruth,
    release: Option<oneshot::Sender<()>>,
}

impl Hold {
    /// Lets the simulator go on.
    pub fn release(mut self) {
        self.send_release();
    }

    fn send_release(&mut self) {
        if let Some(tx) = self.release.take() {
            let _ = tx.send(());
        }
    }
}

impl Drop for Hold {
    fn drop(&mut self) {
        self.send_release();
    }
}

/// A gate and its handle.
pub fn gate(config: GateConfig) -> (Gate, GateHandle) {
    let shared = Arc::new(Shared::default());
    let (tx, rx) = mpsc::channel(1);
    let gate = Gate {
        config,
        shared: shared.clone(),
        to_host: tx,
        next_periodic: config.period.filter(|p| !p.is_zero()).map(|p| SimTime::ZERO.plus(p)),
    };
    (gate, GateHandle { shared, from_sim: rx })
}

impl GateHandle {
    /// Also hold at `t` (simulated time).
    pub fn hold_at(&self, t: SimTime) {
        if let Ok(mut s) = self.shared.instants.lock() {
            s.insert(t);
        }
    }

    /// The next hold, or `None` once the simulator has stopped.
    pub async fn next_hold(&mut self) -> Option<Hold> {
        self.from_sim.recv().await
    }

    /// Holds released after `max_hold` so far.
    pub fn late_releases(&self) -> u64 {
        self.shared.late.load(Ordering::Relaxed)
    }
}

/// How a pass through the gate went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Passage {
    /// No instant was due.
    Open,
    /// Held and released in time.
    Released,
    /// Held, and the release came too late (or never).
    Late,
}

impl Gate {
    /// Holds if simulated time has reached a due instant (`truth.time` is now), until released or
    /// `max_hold` runs out. Every instant at or before now is consumed by the one hold.
    pub async fn pass(&mut self, truth: &GroundTruth) -> Passage {
        let Some(at) = self.due(truth.time) else {
            return Passage::Open;
        };
        let (tx, rx) = oneshot::channel();
        let hold = Hold {
            at,
            truth: *truth,
            release: Some(tx),
        };
        self.shared.holds.fetch_add(1, Ordering::Relaxed);
        let timeout = self.config.max_hold;
        let released = match tokio::time::timeout(timeout, self.to_host.send(hold)).await {
            // A closed channel: no host any more.
            Ok(Err(_)) => return Passage::Open,
            Ok(Ok(())) => matches!(tokio::time::timeout(timeout, rx).await, Ok(Ok(()))),
            Err(_) => false,
        };
        if released {
            Passage::Released
        } else {
            self.shared.late.fetch_add(1, Ordering::Relaxed);
            Passage::Late
        }
    }

    /// Holds so far, and late releases among them.
    pub fn counts(&self) -> (u64, u64) {
        (
            self.shared.holds.load(Ordering::Relaxed),
            self.shared.late.load(Ordering::Relaxed),
        )
    }

    /// The earliest due instant at or before `now`, consuming every one up to `now`.
    fn due(&mut self, now: SimTime) -> Option<SimTime> {
        if self.to_host.is_closed() {
            return None;
        }
        let mut first = None;
        if let (Some(next), Some(p)) = (self.next_periodic, self.config.period)
            && next <= now
        {
            first = Some(next);
            let mut n = next;
            while n <= now {
                n = n.plus(p);
            }
            self.next_periodic = Some(n);
        }
        if let Ok(mut s) = self.shared.instants.lock() {
            let passed: Vec<SimTime> = s.range(..=now).copied().collect();
            for t in &passed {
                s.remove(t);
            }
            first = first.into_iter().chain(passed.first().copied()).min();
        }
        first
    }
}

#[cfg(test)]
mod tests;
