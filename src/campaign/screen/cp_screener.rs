//! The screener of a Collision Prevention campaign: one flight of the Collision Prevention LFS model
//! ([`crate::lfs::cp_model`]) per candidate, with the case's CP parameters. It is deterministic (no wind, no
//! perturbation), so it has no ensemble.

use crate::campaign::ground::screener::{Screened, Screener};
use crate::campaign::screen::lfs_screener::NO_PREDICTION_M;
use crate::judge::Judge;
use crate::lfs::cp_model::{CpEnd, CpSimConfig, simulate_cp};
use crate::lfs::cp_params::CpParams;
use crate::model::{TestCase, Trajectory};

/// Screens candidates with [`simulate_cp`].
#[derive(Debug, Clone, Default)]
pub struct CpScreener {
    /// The judge edition of the predicted distance.
    pub judge: Judge,
}

impl CpScreener {
    fn config(&self) -> CpSimConfig {
        CpSimConfig {
            judge: self.judge,
            ..CpSimConfig::default()
        }
    }
}

impl Screener for CpScreener {
    fn screen(&self, test: &TestCase) -> Screened {
        let cfg = self.config();
        let cp = match CpParams::from_params(&test.params) {
            Ok(cp) => cp,
            Err(e) => return Screened::new(NO_PREDICTION_M, cfg.timeout_s, format!("error: {e}")),
        };
        let p = simulate_cp(test, &cp, &cfg);
        let d = p.min_distance.unwrap_or(NO_PREDICTION_M);
        let (t, status) = match p.end {
            CpEnd::Landed => (p.trajectory.duration_s(), "landed"),
            // A pilot that gives up ends the flight early; rank it as the full timeout, as a flight that never lands.
            CpEnd::Stuck(_) => (cfg.timeout_s, "timeout"),
            CpEnd::Timeout => (cfg.timeout_s, "timeout"),
        };
        Screened::new(d, t, status)
    }

    fn path(&self, test: &TestCase) -> Option<Trajectory> {
        let cp = CpParams::from_params(&test.params).ok()?;
        Some(simulate_cp(test, &cp, &self.config()).trajectory)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Obstacle;

    #[test]
    fn predicts_a_distance_for_boxes_and_none_without() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
        let mut t = TestCase::load(&path).unwrap();
        t.obstacles.clear();
        let s = CpScreener::default().screen(&t);
        assert_eq!((s.min_distance_m, s.ending.as_str()), (NO_PREDICTION_M, "landed"));
        assert!(s.flight_time_s > 10.0 && s.flight_time_s < 200.0, "{s:?}");
        t.obstacles = vec![Obstacle::new(2.0, 2.0, 20.0, -3.0, 27.0, 0.0)];
        let d = CpScreener::default().screen(&t).min_distance_m;
        assert!(d < 10.0, "{d}");
    }
}
