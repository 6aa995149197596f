//! What a learning campaign learns from its journal between rounds: the LFS calibrated on every flight so far
//! ([`crate::campaign::learn::calibration`]), the flights' kernel ([`crate::campaign::learn::surrogate`]) that moves predictions towards the flown
//! distances nearby in draw space, and with `adapt` the generator's histogram refitted on the elites.
//!
//! The refit is a univariate marginal distribution algorithm ([`crate::generator::adaptive`]): elites are the
//! best [`ELITE_SHARE`] of the screened candidates by prediction, plus the closest quarter of the flights and
//! every flown failure at [`FLOWN_FAILURE_WEIGHT`]; each draw's histogram moves [`FIT_RATE`] of the way to
//! theirs and keeps [`UNIFORM_FLOOR`] of uniform mass. It backs off ([`BACKOFF`]) when the failing tests grow
//! alike or a round could not fill its share of the budget.

use crate::campaign::ground::candidate::{Candidate, LfsPrediction, unit_of};
use crate::campaign::learn::calibration::Calibration;
use crate::campaign::learn::surrogate::{KernelPoint, Surrogate};
use crate::campaign::settings::CampaignSettings;
use crate::campaign::store::journal::FlightRecord;
use crate::generator::adaptive::{DIMS, DrawDistribution};
use crate::judge::diversity;
use crate::model::Obstacle;
use crate::model::competition::FAIL_BELOW_M;

/// Below this many failing tests their diversity says little (two tests next to each other score 0.7): it does
/// not back off the fit, and no child may come closer than `--max-iou`. (The diversity guard's expectation,
/// which counts the failures still to come, binds from the first failure.)
pub const MIN_FAILING_FOR_DIVERSITY: usize = 4;
/// Share of the screened candidates that are elites.
pub const ELITE_SHARE: f64 = 0.1;
/// Weight of a flown elite (the closest quarter of the flights, and every failure): a truth counts more than
/// a prediction.
pub const FLOWN_FAILURE_WEIGHT: f64 = 5.0;
/// How far each fit moves the distribution towards the elites'.
pub const FIT_RATE: f64 = 0.7;
/// Uniform mass every fitted draw keeps.
pub const UNIFORM_FLOOR: f64 = 0.2;
/// The backed-off fit (rate, uniform floor) when the failures' diversity is below the user's floor or a round
/// could not fill its share of the budget.
pub const BACKOFF: (f64, f64) = (0.3, 0.5);

/// The prior calibration updated with every journaled flight's raw prediction and flown distance, in order.
pub fn calibrated(prior: &Calibration, done: &[FlightRecord]) -> Calibration {
    let mut c = prior.clone();
    for r in done {
        if let (Some(raw), Some(flown)) = (
            r.prediction.as_ref().and_then(|p| p.raw_min_distance),
            r.flown.min_distance,
        ) {
            c.observe(raw, flown);
        }
    }
    c
}

/// What the journal teaches: the calibration, and the flights' kernel over the flights this run drew.
pub struct Lessons {
    /// The LFS's calibration.
    pub calibration: Calibration,
    points: Vec<KernelPoint>,
    /// The flights' kernel, when there are enough flights to choose one.
    pub kernel: Option<Surrogate>,
}

impl Lessons {
    /// Learns from the flights in `done`, starting from `start`.
    pub fn from(start: &Calibration, done: &[FlightRecord], candidates: &[Candidate]) -> Self {
        // Parallel vehicles journal a round's flights in the order they land; learning in candidate order
        // keeps the campaign a function of its seed.
        let mut done = done.to_vec();
        done.sort_by_key(|r| r.candidate);
        let done = &done[..];
        let calibration = calibrated(start, done);
        let points: Vec<KernelPoint> = done
            .iter()
            .filter_map(|r| {
                Some(KernelPoint {
                    unit: unit_of(candidates, r.candidate)?,
                    lfs_m: calibration.predict(r.prediction.as_ref()?.raw_min_distance?),
                    flown_m: r.flown.min_distance.filter(|d| d.is_finite())?,
                })
            })
            .collect();
        let kernel = Surrogate::fit(&points);
        Self {
            calibration,
            points,
            kernel,
        }
    }

    /// What a round ranks a screened candidate by: the calibrated LFS, moved towards the flights near it.
    pub fn predict(&self, s: &LfsPrediction, candidates: &[Candidate]) -> f64 {
        let lfs = self.calibration.predict(s.min_distance);
        match (&self.kernel, unit_of(candidates, s.candidate)) {
            (Some(k), Some(u)) => k.predict(&u, lfs, &self.points),
            _ => lfs,
        }
    }
}

/// The histogram refitted on the elites after a round: backed off when the round flew fewer than it planned
/// (`starved`: its candidates were near-duplicates of the flown tests) or the failing tests grew alike (once
/// there are enough of them to say so).
pub fn refit(
    distribution: &DrawDistribution,
    candidates: &[Candidate],
    done: &[FlightRecord],
    taught: &Lessons,
    (cfg, starved): (&CampaignSettings, bool),
) -> DrawDistribution {
    let failing: Vec<Vec<Obstacle>> = done
        .iter()
        .filter(|r| r.flown.min_distance.is_some_and(|d| d < FAIL_BELOW_M))
        .map(|r| r.obstacles.clone())
        .collect();
    let below_floor = diversity(&failing).is_some_and(|d| d < cfg.learning.min_diversity);
    let alike = below_floor && failing.len() >= MIN_FAILING_FOR_DIVERSITY;
    let (rate, floor) = if starved || alike {
        BACKOFF
    } else {
        (FIT_RATE, UNIFORM_FLOOR)
    };
    let screened: Vec<&LfsPrediction> = candidates.iter().filter_map(|c| c.prediction.as_ref()).collect();
    let predict = |s: &LfsPrediction| taught.predict(s, candidates);
    distribution.fitted(&elites(&screened, done, candidates, predict), rate, floor)
}

/// The elites: the best share of the screened candidates by `predict`, and the closest quarter of the flights
/// with every flown failure.
pub fn elites(
    screened: &[&LfsPrediction],
    done: &[FlightRecord],
    candidates: &[Candidate],
    predict: impl Fn(&LfsPrediction) -> f64,
) -> Vec<([f64; DIMS], f64)> {
    let mut order: Vec<(&LfsPrediction, f64)> = screened.iter().map(|s| (*s, predict(s))).collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.candidate.cmp(&b.0.candidate)));
    let take = ((order.len() as f64 * ELITE_SHARE).ceil() as usize).max(1);
    let mut out: Vec<([f64; DIMS], f64)> = order
        .iter()
        .take(take)
        .filter_map(|(s, _)| unit_of(candidates, s.candidate).map(|u| (u, 1.0)))
        .collect();
    // The flights are the truth: the closest quarter of them (and every failure) weigh more than a prediction.
    let mut flown: Vec<(&FlightRecord, f64)> = done.iter().filter_map(|r| Some((r, r.flown.min_distance?))).collect();
    flown.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.candidate.cmp(&b.0.candidate)));
    let closest = flown.len().div_ceil(4);
    for (k, (r, d)) in flown.iter().enumerate() {
        if (k < closest || *d < FAIL_BELOW_M)
            && let Some(u) = unit_of(candidates, r.candidate)
        {
            out.push((u, FLOWN_FAILURE_WEIGHT));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::ground::candidate::CandidateId;

    fn record(candidate: u64, raw: f64, flown: f64) -> FlightRecord {
        crate::campaign::store::journal::test_record(candidate, raw, Some(flown))
    }

    #[test]
    fn calibration_replays_the_journal_and_elites_weigh_flown_failures() {
        let done = vec![record(0, 1.0, 2.0), record(1, 1.0, 1.2)];
        let c = calibrated(&Calibration::with_prior(0.0, 1.0), &done);
        // (0 + 1.0 + 0.2) / (1 + 2)
        assert!((c.bias_m() - 0.4).abs() < 1e-12);
        let screened: Vec<LfsPrediction> = (0..10)
            .map(|i| LfsPrediction::point(CandidateId(i), i as f64, 60.0, "landed".into()))
            .collect();
        let units: Vec<[f64; DIMS]> = (0..10).map(|i| [i as f64 / 10.0; DIMS]).collect();
        let candidates: Vec<Candidate> = units.iter().map(|u| Candidate::drawn(Vec::new(), *u)).collect();
        let screened: Vec<&LfsPrediction> = screened.iter().collect();
        let e = elites(&screened, &done, &candidates, |s| c.predict(s.min_distance));
        // The best 10 % (candidate 0), then the closest quarter of the flights, which is also the one failure
        // (candidate 1, 1.2 m), at the flights' weight.
        assert_eq!(e.len(), 2);
        assert_eq!(e[0], ([0.0; DIMS], 1.0));
        assert_eq!(e[1], ([0.1; DIMS], FLOWN_FAILURE_WEIGHT));
        // The report's failure counts: candidate 1 failed in bin 0 of every draw.
        let m = crate::campaign::learn::failure_counts::counted_failures(&done, &candidates);
        assert_eq!((m.total.flights, m.total.failures), (2, 1));
        assert_eq!(m.draws[4][0].failures, 1);
    }
}
