//! What the avoidance companion holds the in-process simulator's time with: its gate's handle (taken once, by
//! the one companion of the flight), its clock, and the home its local NED frame is about.

use std::sync::{Arc, Mutex, PoisonError};

use crate::model::GeoPoint;
use simulator::SimClock;
use simulator::hil::gate::GateHandle;

/// The simulator's gate for the flight's companion; clones share it, and only the first [`SimGate::take`]
/// gets the handle. Until a companion takes it nobody registers an instant, so the simulator never holds.
#[derive(Clone)]
pub struct SimGate {
    handle: Arc<Mutex<Option<GateHandle>>>,
    clock: SimClock,
    home: GeoPoint,
}

impl SimGate {
    /// The gate of a simulator whose clock is `clock` and whose local NED frame is about `home`.
    pub fn new(handle: GateHandle, clock: SimClock, home: GeoPoint) -> Self {
        Self {
            handle: Arc::new(Mutex::new(Some(handle))),
            clock,
            home,
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
}
