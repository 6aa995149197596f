//! The high-fidelity vehicles: the vehicle trait, the jobs it flies and what a fleet's run of them came to (the
//! fleet that flies them is [`crate::campaign::fly::fleet`]).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use crate::campaign::ground::candidate::{CandidateId, LfsPrediction};
use crate::campaign::ground::flight_status::FlightStatus;
// What `Vehicle::fly` returns, defined beside `FlightStatus`: the journal holds it without importing `fly`.
use crate::campaign::fly::confirm::Tally;
pub use crate::campaign::ground::flight_status::Flown;
pub use crate::campaign::ground::stage_times::FleetUse;
use crate::campaign::store::journal::FlightRecord;
use crate::model::TestCase;

/// Why a vehicle could not fly.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VehicleError {
    /// The vehicle cannot be reached or used: the fleet drops it and gives its test to another.
    #[error("vehicle {vehicle} unreachable: {reason}")]
    Unreachable {
        /// The vehicle.
        vehicle: String,
        /// Why.
        reason: String,
    },
}

/// A high-fidelity vehicle: the embedded mock, a PX4 SITL instance or a real flight controller.
pub trait Vehicle: Send {
    /// A name for logs and the journal (a MAVLink URL or `mock`).
    fn name(&self) -> String;
    /// Flies `test`, appending the trajectory to `trajectory_csv`; returns when landed or given up.
    fn fly(&mut self, test: &TestCase, trajectory_csv: &Path, cancel: &AtomicBool) -> Result<Flown, VehicleError>;
}

/// One flight to make.
#[derive(Debug, Clone)]
pub struct Job {
    /// The candidate flown.
    pub candidate: CandidateId,
    /// The candidate's prediction, carried into its flight record (`None`: flown unscreened, or as written).
    pub prediction: Option<LfsPrediction>,
    /// The test to fly.
    pub test: TestCase,
    /// The test's flights before this one (none for a new candidate).
    pub tally: Tally,
    /// Flights a failing test gets at most (`--confirm`): a failing flight whose majority is not settled puts
    /// the test's next flight at the front of the queue.
    pub confirm: usize,
    /// The campaign round that queued it (its re-flights keep it): what [`crate::campaign::fly::fleet::Fleet::wait_round`]
    /// waits for.
    pub round: usize,
}

impl Job {
    /// The first flight of `candidate`, not flown again (`--confirm 1`).
    pub fn new(candidate: CandidateId, prediction: Option<LfsPrediction>, test: TestCase) -> Self {
        Self {
            candidate,
            prediction,
            test,
            tally: Tally::default(),
            confirm: 1,
            round: 0,
        }
    }

    /// The test's next flight after `record` (this job's), if its majority is not settled.
    pub(in crate::campaign) fn again(&self, record: &FlightRecord) -> Option<Job> {
        let tally = self.tally.with(record);
        tally.wants_another(self.confirm).then(|| Job { tally, ..self.clone() })
    }
}

/// What the fleet did.
#[derive(Debug, Default)]
pub struct PoolOutcome {
    /// Flights finished (journaled) in this run.
    pub flown: usize,
    /// Those flights' records in journal order, as the journal reads them back.
    pub records: Vec<FlightRecord>,
    /// Vehicles dropped as unreachable, with the reason.
    pub dropped: Vec<String>,
    /// Journal errors (the flight happened but could not be recorded): the campaign stops on the first.
    pub errors: Vec<String>,
    /// How busy the vehicles were.
    pub fleet: FleetUse,
}

/// A flight the user's stop cut short (`aborted` after the campaign's cancel) is `interrupted`: not charged,
/// flown again first on resume. A flight that ended on its own while the stop came keeps its status.
pub(in crate::campaign) fn interrupted_if_cancelled(mut flown: Flown, cancel: &AtomicBool) -> Flown {
    if flown.status == FlightStatus::ABORTED && cancel.load(Ordering::Relaxed) {
        flown.status = FlightStatus::Interrupted;
        flown.reason = Some(format!(
            "stopped by the user ({}); not charged to the budget, flown again first on --resume",
            flown.reason.as_deref().unwrap_or("cancelled")
        ));
    }
    flown
}

impl Job {
    /// The journal record of this job flown by `vehicle`: its prediction and the vehicle's outcome as they are.
    pub(in crate::campaign) fn record(
        self,
        flown: Flown,
        vehicle: String,
        trajectory: PathBuf,
        wall_s: f64,
    ) -> FlightRecord {
        FlightRecord {
            candidate: self.candidate,
            attempt: self.tally.next_attempt,
            obstacles: self.test.obstacles,
            prediction: self.prediction,
            flown,
            vehicle,
            trajectory,
            wall_s,
        }
    }
}
