//! What the stages ask of the low-fidelity simulator and of the progress display.

use crate::lfs::ensemble::EnsembleParams;
use crate::model::TestCase;

/// Predicts a test's flight with the low-fidelity simulator.
pub trait Screener: Sync {
    /// Predicted minimum distance (m), flight time (s) and how the simulated flight ended.
    fn screen(&self, test: &TestCase) -> (f64, f64, String);

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
