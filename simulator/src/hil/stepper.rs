//! The work of one step, shared by the lockstep (TCP) and wall-clock (serial) links: pass the gate, step
//! the simulation, frame its sensors for PX4, publish the clock and the ground truth; and the handling of
//! what PX4 sends back.

use std::time::Duration;

use tokio::sync::watch;

use super::gate::{Gate, Passage};
use super::link::Outbox;
use super::messages::{self, HIL_STATE_QUATERNION_ID, Incoming, LastReadings};
use crate::sim::{GroundTruth, Simulation};
use crate::time::{SimClock, SimTime};

/// Where the host watches the run.
#[derive(Debug)]
pub struct Observers {
    /// The simulated clock.
    pub clock: SimClock,
    /// The ground truth after every step.
    pub truth: watch::Sender<GroundTruth>,
    /// The gate, if the host installed one.
    pub gate: Option<Gate>,
}

/// The clock HIL messages are stamped with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stamp {
    /// Simulated time: PX4 SITL in lockstep sets its clock from it.
    SimTime,
    /// Wall time since an instant: a board (which ignores it) or SITL fed on the wall clock.
    WallSince(std::time::Instant),
}

/// Counters a run reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StepCounts {
    /// Gate holds released in time.
    pub holds: u64,
    /// Gate holds released late.
    pub late_releases: u64,
    /// HIL_GPS messages sent.
    pub gps_sent: u64,
    /// HIL_STATE_QUATERNION messages sent.
    pub state_sent: u64,
}

/// The per-step state of a link.
#[derive(Debug)]
pub struct Stepper {
    last: LastReadings,
    /// HIL_STATE_QUATERNION interval PX4 asked for (never honoured on a board).
    state_interval: Option<Duration>,
    allow_state: bool,
    next_state: SimTime,
    next_heartbeat: SimTime,
    utc_start_us: u64,
    counts: StepCounts,
}

impl Stepper {
    /// A stepper; `allow_state`: whether HIL_STATE_QUATERNION may be sent (SITL yes, a board never).
    pub fn new(allow_state: bool, utc_start_us: u64) -> Self {
        Self {
            last: LastReadings::default(),
            state_interval: None,
            allow_state,
            next_state: SimTime::ZERO,
            next_heartbeat: SimTime::ZERO,
            utc_start_us,
            counts: StepCounts::default(),
        }
    }

    /// The counters so far.
    pub fn counts(&self) -> StepCounts {
        self.counts
    }

    /// Takes a message from PX4; returns whether it was a motor command.
    pub fn on_incoming(&mut self, sim: &mut Simulation, incoming: &Incoming) -> bool {
        match *incoming {
            Incoming::Actuators { controls, armed, .. } => {
                sim.set_actuators(&controls, armed);
                true
            }
            Incoming::MessageInterval {
                message_id,
                interval_us,
            } if message_id == HIL_STATE_QUATERNION_ID => {
                self.state_interval = (interval_us > 0).then(|| Duration::from_micros(interval_us as u64));
                false
            }
            _ => false,
        }
    }

    /// One step: the gate, the physics, the messages into `out`, stamped on PX4's clock `stamp`.
    pub async fn step(&mut self, sim: &mut Simulation, out: &mut Outbox, obs: &mut Observers, stamp: Stamp) {
        if let Some(gate) = obs.gate.as_mut() {
            match gate.pass(&sim.truth()).await {
                Passage::Open => {}
                Passage::Released => self.counts.holds += 1,
                Passage::Late => self.counts.late_releases += 1,
            }
        }
        let frame = sim.step();
        let now = sim.time();
        let stamp_us = match stamp {
            Stamp::SimTime => now.as_micros(),
            Stamp::WallSince(t0) => t0.elapsed().as_micros() as u64,
        };
        out.push(&messages::hil_sensor(&frame, stamp_us, &mut self.last));
        if let Some(fix) = frame.gps {
            out.push(&messages::hil_gps(&fix, self.utc_start_us + stamp_us));
            self.counts.gps_sent += 1;
        }
        let truth = sim.truth();
        if let Some(interval) = self.state_interval.filter(|_| self.allow_state)
            && now >= self.next_state
        {
            out.push(&messages::hil_state_quaternion(&truth, stamp_us));
            self.next_state = now.plus(interval);
            self.counts.state_sent += 1;
        }
        if now >= self.next_heartbeat {
            out.push(&messages::heartbeat());
            self.next_heartbeat = now.plus(Duration::from_secs(1));
        }
        obs.clock.set(now);
        obs.truth.send_replace(truth);
    }
}
