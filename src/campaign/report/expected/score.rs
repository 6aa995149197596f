//! The campaign aims at the 2026 score: every test that failed gets its expected mean points over 5 flights
//! ([`crate::campaign::report::expected::expected_points`]) from its own flights, its neighbours' (the flown tests whose
//! footprints overlap it by IoU >= [`NEIGHBOUR_IOU`]) and the calibrated prediction; the tests rank by their
//! expected 2026 score (expected points per expected minute, x 10 / obstacles²). Written are those that
//! failed at least once and whose 10 % bound of expected points is above zero, less those whose flown
//! trajectory likely copies a better written test's or would cost the suite more through `sim_pen` than it
//! adds ([`crate::campaign::report::expected::trajectory_guard`]). The suite's expected 2026 score is the sum
//! of the written tests' expected scores times the expected `sim_pen`; its interval is where the judge's
//! score of 5 flights per test will fall.

use std::cmp::Ordering;
use std::path::Path;

use crate::campaign::ground::candidate::CandidateId;
use crate::campaign::report::expected::expected_points::{Evidence, Z80, counts, estimate, skilled_prior};
pub use crate::campaign::report::expected::figures::{SuiteExpectation, TestExpectation};
use crate::campaign::report::expected::trajectory_guard::{
    Guarded, choose, expected_sim_pen, flown_average, guard_below,
};
use crate::campaign::report::suite::DISTINCT_IOU;
use crate::campaign::report::verdicts::TestVerdict;
use crate::campaign::store::journal::FlightRecord;
use crate::geometry::{Footprint, union_iou};
use crate::judge::similarity::SIMILAR_BELOW_M;
use crate::model::Obstacle;
use crate::model::competition::TEST_SCORE_SCALE;

/// Flown tests overlapping a test by at least this footprint IoU are its neighbours: the campaign's own
/// near-duplicate rule, so a neighbour is a test it would not fly as new.
pub const NEIGHBOUR_IOU: f64 = DISTINCT_IOU;

/// Estimates, ranks and chooses the tests to write among `tests` (each with its flights) of the campaign's
/// `records`, setting `expected`, `confirmed` (written) and `near_duplicate_of`; reads the flights'
/// trajectories from `folder`. Returns the written suite's expectation.
pub fn aim(
    folder: &Path,
    records: &[FlightRecord],
    tests: &mut [(TestVerdict, Vec<&FlightRecord>)],
) -> SuiteExpectation {
    let flights = Flights::new(records);
    for (t, own) in tests.iter_mut() {
        t.expected = Some(flights.expectation(t, own));
    }
    tests.sort_by(|a, b| better(&a.0, &b.0));
    let mut candidates = Vec::new();
    let mut earning = Vec::new();
    for (i, (t, own)) in tests.iter_mut().enumerate() {
        t.confirmed = t.failures > 0 && t.expected.is_some_and(|e| e.points.earns());
        if t.confirmed {
            candidates.push((flown_average(folder, own), t.expected.map_or(0.0, |e| e.score)));
            earning.push(i);
        }
    }
    let verdicts = choose(&candidates, SIMILAR_BELOW_M);
    let mut set_aside = 0;
    for (&i, verdict) in earning.iter().zip(&verdicts) {
        match *verdict {
            Guarded::Kept { flag_probability } => tests[i].0.similar_chance = Some(flag_probability),
            Guarded::Copies { kept, dtw_m } => {
                set_aside += 1;
                tests[i].0.confirmed = false;
                tests[i].0.near_duplicate_of = Some(format!("test_{kept}.yaml"));
                tests[i].0.near_duplicate_dtw_m = Some(dtw_m);
            }
        }
    }
    suite(tests.iter().map(|(t, _)| t), set_aside, expected_sim_pen(&verdicts))
}

/// Best first: the higher expected score, then the candidate index.
fn better(a: &TestVerdict, b: &TestVerdict) -> Ordering {
    let score = |t: &TestVerdict| t.expected.map_or(0.0, |e| e.score);
    score(b).total_cmp(&score(a)).then(a.candidate.cmp(&b.candidate))
}

/// The written suite's figures.
fn suite<'a>(tests: impl Iterator<Item = &'a TestVerdict>, near_duplicates: usize, pen: f64) -> SuiteExpectation {
    let written: Vec<TestExpectation> = tests.filter(|t| t.confirmed).filter_map(|t| t.expected).collect();
    let sum = |f: fn(&TestExpectation) -> f64| written.iter().map(f).sum::<f64>() + 0.0;
    let total_score = sum(|e| e.score);
    let sd = sum(|e| e.score_sd * e.score_sd).sqrt();
    let (total_low, total_high) = ((total_score - Z80 * sd).max(0.0), total_score + Z80 * sd);
    SuiteExpectation {
        tests: written.len(),
        near_duplicates,
        similar_below_m: SIMILAR_BELOW_M,
        guard_below_m: guard_below(SIMILAR_BELOW_M),
        total_score,
        total_low,
        total_high,
        sim_pen: pen,
        final_score: total_score * pen,
        final_low: total_low * pen,
        final_high: total_high * pen,
    }
}

/// What every estimate reads of the campaign's flights, computed once: each flight's footprints, and its
/// (calibrated prediction, flown distance) pair.
pub struct Flights<'a> {
    records: &'a [FlightRecord],
    prints: Vec<Vec<Footprint>>,
    predicted_flown: Vec<(CandidateId, (f64, f64))>,
}

fn prints(o: &[Obstacle]) -> Vec<Footprint> {
    o.iter().map(Obstacle::footprint).collect()
}

impl<'a> Flights<'a> {
    /// The campaign's charged flights.
    pub fn new(records: &'a [FlightRecord]) -> Self {
        let predicted_flown = (records.iter())
            .filter_map(|r| {
                Some((
                    r.candidate,
                    (r.predicted_m().filter(|d| d.is_finite())?, r.flown.min_distance?),
                ))
            })
            .collect();
        Self {
            records,
            prints: records.iter().map(|r| prints(&r.obstacles)).collect(),
            predicted_flown,
        }
    }

    /// What the estimate of `candidate` (with `obstacles` and its flights `own`) rests on. The prior is its
    /// first flight's prediction, weighed and spread by the other tests' flights (its own would count its
    /// flights twice).
    fn evidence(&self, candidate: CandidateId, obstacles: &[Obstacle], own: &[&FlightRecord]) -> Evidence {
        let mine = prints(obstacles);
        let neighbours = (self.records.iter().zip(&self.prints))
            .filter(|(r, p)| r.candidate != candidate && union_iou(&mine, p) >= NEIGHBOUR_IOU)
            .filter_map(|(r, _)| r.flown.min_distance);
        let others: Vec<(f64, f64)> = (self.predicted_flown.iter())
            .filter(|(c, _)| *c != candidate)
            .map(|(_, pair)| *pair)
            .collect();
        // No prediction (a test flown unscreened): NaN, and the prior leans on the flights alone.
        let first = own.iter().min_by_key(|r| r.attempt);
        let predicted = first.and_then(|r| r.predicted_m()).unwrap_or(f64::NAN);
        Evidence {
            own: counts(own.iter().filter_map(|r| r.flown.min_distance)),
            neighbours: counts(neighbours),
            prior: skilled_prior(predicted, &others),
        }
    }

    /// The expectation of test `t` with its flights `own`.
    pub fn expectation(&self, t: &TestVerdict, own: &[&FlightRecord]) -> TestExpectation {
        let points = estimate(&self.evidence(t.candidate, &t.obstacles, own));
        let flown: Vec<f64> = (own.iter())
            .filter(|r| r.flown.min_distance.is_some())
            .map(|r| r.flown.flight_time_s)
            .collect();
        let seconds = if flown.is_empty() {
            (own.first().and_then(|r| r.prediction.as_ref())).map_or(0.0, |p| p.flight_time_s)
        } else {
            flown.iter().sum::<f64>() / flown.len() as f64
        };
        let minutes = seconds / 60.0;
        let k = t.obstacles.len() as f64;
        let score = |p: f64| {
            if minutes > 0.0 && k > 0.0 {
                p * TEST_SCORE_SCALE / (k * k * minutes)
            } else {
                0.0
            }
        };
        TestExpectation {
            points,
            minutes,
            score: score(points.mean),
            score_low: score(points.judged_low),
            score_high: score(points.judged_high),
            score_sd: score(points.judged_sd),
        }
    }
}

/// The summary table's rows of the written suite's expected 2026 score (none without an expectation).
pub fn markdown_rows(md: &mut String, e: Option<&SuiteExpectation>) {
    use std::fmt::Write as _;
    let Some(e) = e else { return };
    let _ = writeln!(
        md,
        "| expected 2026 score of the written tests (10-90 % of the judge's 5 flights each): sum of expected test \
         scores x sim_pen | {:.3} \
         ({:.3}-{:.3}) = {:.3} x {:.3} |",
        e.final_score, e.final_low, e.final_high, e.total_score, e.sim_pen
    );
    let _ = writeln!(
        md,
        "| tests set aside as near-duplicate trajectories (more likely than not similar for the judge: DTW < {:.0} \
         m to a better written test; or costing more through sim_pen than they add) | {} |",
        e.guard_below_m, e.near_duplicates
    );
}

#[cfg(test)]
#[path = "score_tests.rs"]
mod tests;
