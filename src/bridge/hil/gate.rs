//! What the avoidance companion holds the in-process simulator's time with: its gate's handle (taken once, by
//! the one companion of the flight), its clock, and the home its local NED frame is about. The session may ask
//! for a turn at one of the companion's holds ([`SimGate::turn_at`]): what it sends then reaches PX4 while its
//! clock stands still, so PX4 takes it at the same simulated instant in every run.

use std::sync::{Arc, Mutex, PoisonError};
use std::time::Duration;

use tokio::sync::oneshot;

use crate::model::GeoPoint;
use simulator::hil::gate::GateHandle;
use simulator::{SimClock, SimTime};

/// A session waiting for its turn: the first hold at or after `from` hands it `go`.
struct Waiting {
    from: SimTime,
    go: oneshot::Sender<Turn>,
}

/// A turn at a hold: simulated time stands still until it is dropped (the companion waits for that, bounded).
pub struct Turn {
    /// The hold's instant.
    pub at: SimTime,
    done: Option<oneshot::Sender<()>>,
}

impl Drop for Turn {
    fn drop(&mut self) {
        if let Some(d) = self.done.take() {
            let _ = d.send(());
        }
    }
}

/// The simulator's gate for the flight's companion; clones share it, and only the first [`SimGate::take`]
/// gets the handle. Until a companion takes it nobody registers an instant, so the simulator never holds.
#[derive(Clone)]
pub struct SimGate {
    handle: Arc<Mutex<Option<GateHandle>>>,
    clock: SimClock,
    home: GeoPoint,
    waiting: Arc<Mutex<Vec<Waiting>>>,
}

impl SimGate {
    /// The gate of a simulator whose clock is `clock` and whose local NED frame is about `home`.
    pub fn new(handle: GateHandle, clock: SimClock, home: GeoPoint) -> Self {
        Self {
            handle: Arc::new(Mutex::new(Some(handle))),
            clock,
            home,
            waiting: Arc::default(),
        }
    }

    /// A turn at the first of the companion's holds at or after `from`, waiting at most `within` (wall time);
    /// `None` when no hold came (no companion holds this simulator, or it stopped).
    pub async fn turn_at(&self, from: SimTime, within: Duration) -> Option<Turn> {
        let (go, turn) = oneshot::channel();
        self.waiting
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(Waiting { from, go });
        tokio::time::timeout(within, turn).await.ok()?.ok()
    }

    /// The companion, at its hold at `at`: hands each session whose instant has come its turn and waits (at
    /// most `within` of wall time each) until it is done.
    pub async fn serve_turns(&self, at: SimTime, within: Duration) {
        let due: Vec<Waiting> = {
            let mut w = self.waiting.lock().unwrap_or_else(PoisonError::into_inner);
            let (due, later) = w.drain(..).partition(|x| x.from <= at);
            *w = later;
            due
        };
        for w in due {
            let (done, finished) = oneshot::channel();
            let turn = Turn { at, done: Some(done) };
            if w.go.send(turn).is_ok() {
                let _ = tokio::time::timeout(within, finished).await;
            }
        }
    }

    /// The handle, once: a second companion (or a second flight) gets `None` and must not pace on it.
    pub fn take(&self) -> Option<GateHandle> {
        self.handle.lock().unwrap_or_else(PoisonError::into_inner).take()
    }

    /// The simulator's clock (simulated time, PX4's own in lockstep).
    pub fn clock(&self) -> SimClock {
        self.clock.clone()
    }

    /// The origin of the simulator's local NED frame (where it put the vehicle at rest, metres AMSL).
    pub fn home(&self) -> GeoPoint {
        self.home
    }
}

impl PartialEq for SimGate {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.handle, &other.handle)
    }
}

impl std::fmt::Debug for SimGate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimGate")
            .field("now", &self.clock.now())
            .field("home", &self.home)
            .finish_non_exhaustive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use simulator::hil::gate::{GateConfig, gate};

    #[test]
    fn the_handle_is_taken_once_and_clones_are_the_same_gate() {
        let (_gate, handle) = gate(GateConfig::default());
        let g = SimGate::new(handle, SimClock::default(), crate::model::SIM_HOME);
        let h = g.clone();
        assert_eq!(g, h);
        assert!(h.take().is_some());
        assert!(g.take().is_none(), "one companion per flight");
        let (_other, handle) = gate(GateConfig::default());
        assert_ne!(g, SimGate::new(handle, SimClock::default(), crate::model::SIM_HOME));
    }

    #[tokio::test]
    async fn a_turn_comes_at_the_first_hold_from_its_instant_and_holds_time_until_dropped() {
        let (_gate, handle) = gate(GateConfig::default());
        let g = SimGate::new(handle, SimClock::default(), crate::model::SIM_HOME);
        let session = g.clone();
        let waiter = tokio::spawn(async move {
            let turn = session
                .turn_at(SimTime::from_millis(1000), Duration::from_secs(5))
                .await;
            let at = turn.as_ref().map(|t| t.at);
            tokio::time::sleep(Duration::from_millis(50)).await;
            drop(turn);
            at
        });
        while g.waiting.lock().unwrap().is_empty() {
            tokio::task::yield_now().await;
        }
        g.serve_turns(SimTime::from_millis(900), Duration::from_secs(1)).await;
        assert_eq!(g.waiting.lock().unwrap().len(), 1, "not due before its instant");
        let t0 = std::time::Instant::now();
        g.serve_turns(SimTime::from_millis(1000), Duration::from_secs(1)).await;
        assert!(
            t0.elapsed() >= Duration::from_millis(40),
            "the hold lasts as long as the turn"
        );
        assert_eq!(waiter.await.unwrap(), Some(SimTime::from_millis(1000)));
        let none = g.turn_at(SimTime::ZERO, Duration::from_millis(20)).await;
        assert!(none.is_none(), "no hold came within the bound");
        let t0 = std::time::Instant::now();
        g.serve_turns(SimTime::from_millis(1100), Duration::from_secs(1)).await;
        assert!(
            t0.elapsed() < Duration::from_millis(20),
            "a session that gave up is not waited for"
        );
    }
}
