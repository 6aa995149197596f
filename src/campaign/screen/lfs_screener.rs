//! The low-fidelity screener: one simulated flight per candidate with the 3DVFH* LFS, and an ensemble of
//! perturbed flights for the shortlisted ones.

use crate::campaign::ground::screener::{Screened, Screener};
use crate::lfs::ensemble::{EnsembleParams, run_ensemble};
use crate::lfs::sim::{SimConfig, SimStatus, simulate};
use crate::model::TestCase;

/// Predicted distance when a simulation cannot judge anything (kept finite so journals stay valid JSON).
pub const NO_PREDICTION_M: f64 = 1e9;

/// Screens candidates with [`simulate`].
#[derive(Debug, Clone, Default)]
pub struct LfsScreener {
    /// Simulation settings (motion model, camera, limits).
    pub config: SimConfig,
    /// Perturbation scales and prior of the ensemble.
    pub ensemble: EnsembleParams,
}

impl Screener for LfsScreener {
    fn screen(&self, test: &TestCase) -> Screened {
        match simulate(test, &self.config) {
            Ok(r) => {
                let d = r.distance.map_or(NO_PREDICTION_M, |d| d.min_distance);
                // A flight that never lands would run into the competition's timeout, and its score shrinks
                // with flight time: rank it as the full timeout.
                let t = if r.status == SimStatus::Landed || r.status == SimStatus::Collision {
                    r.flight_time_s
                } else {
                    self.config.timeout_s
                };
                let status = serde_json::to_value(r.status)
                    .ok()
                    .and_then(|v| v.as_str().map(String::from));
                Screened::new(d, t, status.unwrap_or_else(|| "unknown".into()))
            }
            Err(e) => Screened::new(NO_PREDICTION_M, self.config.timeout_s, format!("error: {e}")),
        }
    }

    fn path(&self, test: &TestCase) -> Option<crate::model::Trajectory> {
        simulate(test, &self.config).ok().map(|r| r.trajectory)
    }

    fn ensemble(&self, test: &TestCase, n: usize, seed: u64) -> Option<Vec<f64>> {
        // One thread per candidate: the campaign already runs a candidate per core.
        let e = run_ensemble(
            &test.mission,
            &test.obstacles,
            &test.params,
            &self.config,
            &self.ensemble,
            n,
            seed,
            1,
        )
        .ok()?;
        Some(e.member_min_distances)
    }

    fn ensemble_params(&self) -> EnsembleParams {
        self.ensemble
    }
}
