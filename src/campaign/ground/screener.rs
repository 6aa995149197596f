//! What the stages ask of the low-fidelity simulator and of the progress display.

use crate::lfs::ensemble::EnsembleParams;
use crate::model::TestCase;

/// What the low-fidelity simulator predicts of one test's flight.
#[derive(Debug, Clone, PartialEq)]
pub struct Screened {
    /// Predicted minimum distance (the campaign's judge), metres.
    pub min_distance_m: f64,
    /// Predicted flight time, seconds (the full timeout for a flight that never lands).
    pub flight_time_s: f64,
    /// How the simulated flight ended, in words (`landed`, `timeout`, `error: ...`).
    pub ending: String,
}

impl Screened {
    /// A prediction of `min_distance_m` over `flight_time_s` that ended `ending`.
    pub fn new(min_distance_m: f64, flight_time_s: f64, ending: impl Into<String>) -> Self {
        Self {
            min_distance_m,
            flight_time_s,
            ending: ending.into(),
        }
    }
}

/// Predicts a test's flight with the low-fidelity simulator.
pub trait Screener: Sync {
    /// The prediction of `test`'s flight.
    fn screen(&self, test: &TestCase) -> Screened;

    /// The predicted path, for plots (`None` if the screener has none).
    fn path(&self, _test: &TestCase) -> Option<crate::model::Trajectory> {
        None
    }

    /// The minimum distances of an ensemble of `n` perturbed simulations drawn from `seed` (`None` if the
    /// screener has no ensemble or the test cannot be simulated).
    fn ensemble(&self, _test: &TestCase, _n: usize, _seed: u64) -> Option<Vec<f64>> {
        None
    }

    /// The prior of `p_fail` over the members.
    fn ensemble_params(&self) -> EnsembleParams {
        EnsembleParams::default()
    }
}

/// Progress reporting for the stages.
pub trait Progress: Sync {
    /// A stage starts with `total` steps.
    fn stage(&self, name: &str, total: usize);
    /// `done` steps of the current stage are finished.
    fn tick(&self, done: usize);
    /// A line for the user.
    fn note(&self, message: &str);
    /// A line the user must see even when progress is quiet (the campaign changed something of theirs).
    fn warn(&self, message: &str) {
        eprintln!("warning: {message}");
    }
}
