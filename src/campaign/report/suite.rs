//! The suite's numbers in a campaign report: what was found (failing tests, scores, diversity, confirmation)
//! and how well the LFS predicted the vehicle's flights.

use serde::Serialize;

use crate::campaign::fly::confirm::{failed_again, first_flights};
use crate::campaign::report::expected::figures::SuiteExpectation;
use crate::campaign::report::verdicts::{TestVerdict, score_sum};
use crate::campaign::store::journal::{FlightRecord, flights_charged};
use crate::judge::{distinct_tests, diversity};
use crate::lfs::fidelity::aggregate;
use crate::model::Obstacle;
use crate::model::competition::FAIL_BELOW_M;

/// Two failing tests overlapping more than this (IoU) count as one place in [`SuiteSummary::distinct_failing`]:
/// the campaign's default `--max-iou`, its near-duplicate rule.
pub const DISTINCT_IOU: f64 = 0.5;

/// The suite's numbers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SuiteSummary {
    /// Candidates drawn and screened.
    pub candidates_screened: usize,
    /// Flights made.
    pub flown: usize,
    /// Written tests: expected to earn 2026 points, less near-duplicate trajectories.
    pub failing: usize,
    /// Sum of the reported tests' scores (each over its flights).
    pub failure_score: f64,
    /// Diversity of the reported tests (1 - mean pairwise IoU).
    pub diversity: Option<f64>,
    /// Reported tests, best first, that overlap no better one kept by more than [`DISTINCT_IOU`]: the failures
    /// counted once per place ([`distinct_tests`]).
    pub distinct_failing: usize,
    /// Reported tests with three obstacles (the extended family's second S); each scores 4/9 of the same
    /// failure with two (the competition divides by the number of obstacles squared).
    #[serde(default)]
    pub failing_with_three: usize,
    /// Of the flown tests the LFS predicted below 1.5 m, the share that flew below 1.5 m.
    pub lfs_precision: Option<f64>,
    /// Mean |predicted - flown| minimum distance over flown tests, metres.
    pub lfs_mean_abs_error_m: Option<f64>,
    /// Brier score of the ensemble's `p_fail` against the flown outcome (below 1.5 m), over the flown tests
    /// that had an ensemble (the flown tests are the ranking's top, so this is not a random sample).
    pub lfs_p_fail_brier: Option<f64>,
    /// Mean |predicted - flown| over the first quarter of the flights (in flight order), with the prediction
    /// the campaign ranked by (in a learning campaign: calibrated, and moved by the flights' kernel), metres.
    pub lfs_error_first_quarter_m: Option<f64>,
    /// The same over the last quarter.
    pub lfs_error_last_quarter_m: Option<f64>,
    /// Spearman rank correlation of the prediction the campaign ranked by (in a learning campaign: calibrated,
    /// and moved by the flights' kernel) against the flown distance, over first flights: whether the LFS
    /// orders this vehicle's flights at all (docs/design-constants.md#lfs-rank-agreement-on-px4).
    #[serde(default)]
    pub lfs_spearman: Option<f64>,
    /// Candidates screened per second of screening wall time (0 without screening).
    pub screening_per_s: f64,
    /// Flights a failing test gets at most (`--confirm`).
    pub confirm: usize,
    /// Tests that failed at least once, confirmed or not.
    pub failed_once: usize,
    /// The failure score over those.
    pub failure_score_failed_once: f64,
    /// Their diversity.
    pub diversity_failed_once: Option<f64>,
    /// Flights that flew a test again (its second flight on).
    pub reflights: usize,
    /// Tests flown again after failing their first flight.
    pub flown_again: usize,
    /// Of those, the ones whose second flight failed too.
    pub failed_again: usize,
    /// `failed_again / flown_again`: how often a first failure repeats.
    pub confirmation_rate: Option<f64>,
    /// The written suite's expected 2026 score (set by the caller).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub expected_2026: Option<SuiteExpectation>,
}

/// Mean |predicted - flown| of the first (or last) quarter of the flights with a flown distance.
fn quarter_error(records: &[FlightRecord], last: bool) -> Option<f64> {
    let e: Vec<f64> = records
        .iter()
        .filter_map(|r| Some((r.flown.min_distance? - r.predicted_m()?).abs()))
        .collect();
    let q = e.len().div_ceil(4);
    if q == 0 {
        return None;
    }
    let part = if last { &e[e.len() - q..] } else { &e[..q] };
    Some(part.iter().sum::<f64>() / q as f64)
}

/// The suite's numbers over the flights `records` and the `tests` that failed at least once (the screening
/// counts and `confirm` are left for the caller); the LFS's accuracy only if the campaign `screened`, over
/// each test's first flight (its later flights were chosen by the first one's outcome, not by the ranking).
pub(in crate::campaign) fn summary(records: &[FlightRecord], tests: &[TestVerdict], screened: bool) -> SuiteSummary {
    let firsts = first_flights(records);
    let predicted_fail: Vec<&FlightRecord> = firsts
        .iter()
        .filter(|r| r.predicted_m().is_some_and(|p| p < FAIL_BELOW_M))
        .collect();
    let precision = (!predicted_fail.is_empty()).then(|| {
        predicted_fail
            .iter()
            .filter(|r| r.flown.min_distance.is_some_and(|d| d < FAIL_BELOW_M))
            .count() as f64
            / predicted_fail.len() as f64
    });
    let errors: Vec<f64> = firsts
        .iter()
        .filter_map(|r| Some((r.flown.min_distance? - r.predicted_m()?).abs()))
        .collect();
    let (p_fail, failed): (Vec<f64>, Vec<bool>) = firsts
        .iter()
        .filter_map(|r| Some((r.prediction.as_ref()?.p_fail?, r.flown.min_distance? < FAIL_BELOW_M)))
        .unzip();
    let confirmed = || tests.iter().filter(|t| t.confirmed);
    let failing_obstacles: Vec<Vec<Obstacle>> = confirmed().map(|t| t.obstacles.clone()).collect();
    let failed_once: Vec<Vec<Obstacle>> = tests.iter().map(|t| t.obstacles.clone()).collect();
    let (again, flown_again) = failed_again(records);
    SuiteSummary {
        candidates_screened: 0,
        flown: flights_charged(records),
        failing: failing_obstacles.len(),
        failure_score: score_sum(confirmed()),
        diversity: diversity(&failing_obstacles),
        distinct_failing: distinct_tests(&failing_obstacles, DISTINCT_IOU),
        failing_with_three: failing_obstacles.iter().filter(|o| o.len() == 3).count(),
        lfs_precision: precision.filter(|_| screened),
        lfs_mean_abs_error_m: (screened && !errors.is_empty())
            .then(|| errors.iter().sum::<f64>() / errors.len() as f64),
        lfs_p_fail_brier: crate::lfs::calibration::brier(&p_fail, &failed),
        lfs_error_first_quarter_m: quarter_error(&firsts, false).filter(|_| screened),
        lfs_error_last_quarter_m: quarter_error(&firsts, true).filter(|_| screened),
        lfs_spearman: spearman_first(&firsts).filter(|_| screened),
        screening_per_s: 0.0,
        confirm: 1,
        failed_once: tests.len(),
        failure_score_failed_once: score_sum(tests.iter()),
        diversity_failed_once: diversity(&failed_once),
        reflights: records.iter().filter(|r| r.attempt > 0).count(),
        flown_again,
        failed_again: again,
        confirmation_rate: (flown_again > 0).then(|| again as f64 / flown_again as f64),
        expected_2026: None,
    }
}

/// Spearman of the ranked prediction against the flown distance over `firsts` (the flights with a distance).
fn spearman_first(firsts: &[FlightRecord]) -> Option<f64> {
    let pairs: Vec<(f64, f64)> = firsts
        .iter()
        .filter_map(|r| Some((r.predicted_m()?, r.flown.min_distance?)))
        .collect();
    aggregate(&pairs).spearman
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::store::journal::test_record;

    #[test]
    fn the_lfs_ranking_figure_is_over_first_flights_and_only_when_screened() {
        // Predictions 1.0, 2.0, 3.0 flown in the reverse order; a repeat of test 0 does not count.
        let mut records: Vec<FlightRecord> = (0..3)
            .map(|i| test_record(i, 1.0 + i as f64, Some(3.0 - i as f64)))
            .collect();
        records.push(FlightRecord {
            attempt: 1,
            ..test_record(0, 1.0, Some(5.0))
        });
        let s = summary(&records, &[], true);
        assert!((s.lfs_spearman.unwrap() + 1.0).abs() < 1e-12, "{:?}", s.lfs_spearman);
        assert_eq!(summary(&records, &[], false).lfs_spearman, None);
    }
}
