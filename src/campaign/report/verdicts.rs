//! Each flown test's verdict over its flights (`--confirm`): how many failed, the 90 % Wilson interval of its
//! failure rate, whether it is confirmed, and its ranking, best first. With one flight per test every failing
//! test is confirmed and the ranking is the flights' (smallest distance, then shorter flight).

use crate::campaign::ground::candidate::CandidateId;
use std::cmp::Ordering;
use std::path::PathBuf;

use serde::Serialize;

use crate::campaign::fly::confirm::{failed, tallies};
use crate::campaign::report::expected::figures::TestExpectation;
use crate::campaign::store::journal::FlightRecord;
use crate::judge::{AboveTop, Z90, test_score, wilson_interval};
use crate::model::Obstacle;

/// A flown test that failed at least once.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TestVerdict {
    /// The candidate index.
    pub candidate: CandidateId,
    /// Its obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Its flights.
    pub flights: usize,
    /// The failing ones among them (below 1.5 m).
    pub failures: usize,
    /// failures / flights.
    pub failure_rate: f64,
    /// The lower bound of the failure rate's 90 % Wilson score interval.
    pub failure_rate_low: f64,
    /// Its upper bound.
    pub failure_rate_high: f64,
    /// Written as `test_N.yaml`: more than half of its `--confirm` flights failed, until the campaign aims
    /// at the 2026 score ([`crate::campaign::report::expected::score`]) and writes by expected points.
    pub confirmed: bool,
    /// Its majority is settled (false: the budget ran out before its confirmation).
    pub settled: bool,
    /// The smallest flown distance of its failing flights, metres.
    pub best_min_distance: f64,
    /// The competition's test score over its flights with a distance.
    pub test_score: f64,
    /// Its flights' trajectories (relative to the campaign folder), the best failing flight first, then the
    /// others in flight order.
    pub trajectories: Vec<PathBuf>,
    /// The file it is written as: `test_N.yaml` when confirmed, else `unconfirmed/test_K.yaml`.
    pub reported_as: Option<String>,
    /// Its expected 2026 figures ([`crate::campaign::report::expected::score`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub expected: Option<TestExpectation>,
    /// The better written test whose flown trajectory it copies (`test_K.yaml`): set aside, not written.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub near_duplicate_of: Option<String>,
    /// The DTW distance between its flown average and that test's (metres, x, y, z).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub near_duplicate_dtw_m: Option<f64>,
    /// For a written test: the chance that the judge finds it too similar to a better written test.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub similar_chance: Option<f64>,
    /// For a written test: set when its closest failing flight was above the box's top at its closest
    /// approach. The 2026 judge is horizontal only: it scores a crossing over a box 0 m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub above_top: Option<AboveTop>,
    /// Where its first flight is in the journal (sums over the tests follow the journal, as over flights).
    #[serde(skip)]
    pub first_flight: usize,
}

/// Every test that failed at least once, best first (see `rank`), confirmed against `confirm` flights;
/// with the records of each test's flights, its best failing flight first.
pub fn verdicts(records: &[FlightRecord], confirm: usize) -> Vec<(TestVerdict, Vec<&FlightRecord>)> {
    let mut out = Vec::new();
    for (candidate, (tally, _)) in tallies(records) {
        if tally.failures == 0 {
            continue;
        }
        let mut flights: Vec<(usize, &FlightRecord)> = (records.iter().enumerate())
            .filter(|(_, r)| r.candidate == candidate)
            .collect();
        flights.sort_by_key(|(_, r)| r.attempt);
        let first_flight = flights[0].0;
        let mut flights: Vec<&FlightRecord> = flights.into_iter().map(|(_, r)| r).collect();
        let best = (0..flights.len())
            .filter(|&i| failed(flights[i].flown.min_distance))
            .min_by(|&a, &b| better_failure(flights[a], flights[b]))
            .unwrap_or(0);
        let best_flight = flights.remove(best);
        flights.insert(0, best_flight);
        let (distances, times): (Vec<f64>, Vec<f64>) = flights
            .iter()
            .filter_map(|r| Some((r.flown.min_distance?, r.flown.flight_time_s)))
            .unzip();
        let (low, high) = wilson_interval(tally.failures, tally.flights, Z90);
        let verdict = TestVerdict {
            candidate,
            obstacles: best_flight.obstacles.clone(),
            flights: tally.flights,
            failures: tally.failures,
            failure_rate: tally.failures as f64 / tally.flights as f64,
            failure_rate_low: low,
            failure_rate_high: high,
            confirmed: tally.confirmed(confirm),
            settled: !tally.wants_another(confirm),
            best_min_distance: best_flight.flown.min_distance.unwrap_or(f64::INFINITY),
            test_score: test_score(&distances, &times, best_flight.obstacles.len()),
            trajectories: flights.iter().map(|r| r.trajectory.clone()).collect(),
            reported_as: None,
            expected: None,
            near_duplicate_of: None,
            near_duplicate_dtw_m: None,
            similar_chance: None,
            above_top: None,
            first_flight,
        };
        out.push((verdict, flights));
    }
    out.sort_by(|a, b| rank(&a.0, &b.0, a.1[0], b.1[0]));
    out
}

/// The smaller flown distance first, then the shorter flight.
fn better_failure(a: &FlightRecord, b: &FlightRecord) -> Ordering {
    let d = |r: &FlightRecord| r.flown.min_distance.unwrap_or(f64::INFINITY);
    d(a).total_cmp(&d(b))
        .then(a.flown.flight_time_s.total_cmp(&b.flown.flight_time_s))
}

/// Best first: the surest failure (highest Wilson lower bound of the failure rate, then the highest rate), then
/// the best failing flight (`fa`, `fb`: smallest distance, shorter flight), then the candidate index.
fn rank(a: &TestVerdict, b: &TestVerdict, fa: &FlightRecord, fb: &FlightRecord) -> Ordering {
    (b.failure_rate_low.total_cmp(&a.failure_rate_low))
        .then(b.failure_rate.total_cmp(&a.failure_rate))
        .then(better_failure(fa, fb))
        .then(a.candidate.cmp(&b.candidate))
}

/// Sum of the tests' scores in the order their first flights were journaled.
pub fn score_sum<'a>(tests: impl Iterator<Item = &'a TestVerdict>) -> f64 {
    let mut t: Vec<&TestVerdict> = tests.collect();
    t.sort_by_key(|v| v.first_flight);
    t.iter().map(|v| v.test_score).sum::<f64>() + 0.0 // an empty sum is -0.0, printed "-0.00"
}

/// The tests that failed, best first, for report.md: the written ones, then those that were not.
pub fn markdown(md: &mut String, tests: &[TestVerdict], confirm: usize) {
    use std::fmt::Write as _;
    if tests.is_empty() {
        let _ = writeln!(
            md,
            "## Tests that failed\n\nNone: no flight came closer than {} m to a box.\n",
            crate::model::competition::FAIL_BELOW_M
        );
        return;
    }
    let flown = if confirm > 1 {
        format!("A failing test was flown again until the majority of {confirm} flights was settled (`--confirm`).")
    } else {
        "Each test was flown once (`--confirm 1`: a failing test is not flown again).".to_string()
    };
    let _ = writeln!(
        md,
        "## Tests that failed\n\n{flown} Ranked by the expected 2026 test score (expected points of a flight, from \
         its flights, its neighbours' and the calibrated prediction, per expected minute); written when the 10 % \
         bound of its expected points is above zero and its flown trajectory copies no better written test's.\n"
    );
    let _ = writeln!(
        md,
        "| candidate | failed / flights | failure rate (90 % interval) | best flown m | expected points (10-90 %) | \
         the judge's 5-flight mean (10-90 %) | expected score | verdict |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for t in tests {
        let file = t.reported_as.as_deref().unwrap_or_default();
        let verdict = match (t.confirmed, &t.near_duplicate_of, t.settled) {
            (true, _, _) => file.to_string(),
            (false, Some(better), _) => format!(
                "near-duplicate of {better} (DTW {:.0} m): {file}",
                t.near_duplicate_dtw_m.unwrap_or(f64::NAN)
            ),
            (false, None, true) => format!("unconfirmed: {file}"),
            (false, None, false) => format!("unconfirmed (budget spent before its confirmation): {file}"),
        };
        let (points, judged, score) = t.expected.map_or(("n/a".into(), "n/a".into(), "n/a".into()), |e| {
            let p = e.points;
            (
                format!("{:.2} ({:.2}-{:.2})", p.mean, p.low, p.high),
                format!("{:.1}-{:.1}", p.judged_low, p.judged_high),
                format!("{:.3}", e.score),
            )
        });
        let _ = writeln!(
            md,
            "| {} | {} / {} | {:.2} ({:.2}-{:.2}) | {:.3} | {points} | {judged} | {score} | {verdict} |",
            t.candidate,
            t.failures,
            t.flights,
            t.failure_rate,
            t.failure_rate_low,
            t.failure_rate_high,
            t.best_min_distance,
        );
    }
    let _ = writeln!(md);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::store::journal::test_record;

    #[test]
    fn no_failing_test_is_said_in_words_rather_than_as_an_empty_table() {
        let mut md = String::new();
        markdown(&mut md, &[], 1);
        assert!(md.contains("None: no flight came closer than 1.5 m"), "{md}");
        assert!(!md.contains("|---|") && !md.contains("majority of 1 flights"), "{md}");
    }

    fn flight(candidate: u64, attempt: u32, d: f64, time_s: f64) -> FlightRecord {
        let mut r = FlightRecord {
            attempt,
            trajectory: format!("c{candidate}_{attempt}.csv").into(),
            ..test_record(candidate, 1.0, Some(d))
        };
        r.flown.flight_time_s = time_s;
        r
    }

    #[test]
    fn tests_rank_by_the_surest_failure_then_the_best_flight() {
        let records = [
            flight(1, 0, 0.5, 60.0),
            flight(2, 0, 1.0, 60.0),
            flight(3, 0, 2.0, 60.0),
            flight(1, 1, 2.0, 60.0),
            flight(2, 1, 1.2, 60.0),
            flight(4, 0, 1.4, 60.0),
            flight(1, 2, 1.0, 60.0),
            flight(4, 1, 1.3, 30.0),
        ];
        let v = verdicts(&records, 3);
        let order: Vec<(u64, usize, usize, bool)> = v
            .iter()
            .map(|(t, _)| (t.candidate.0, t.failures, t.flights, t.confirmed))
            .collect();
        // 2 and 4 failed 2 of 2 (2's best flight is closer), 1 failed 2 of 3; 3 never failed.
        assert_eq!(order, [(2, 2, 2, true), (4, 2, 2, true), (1, 2, 3, true)]);
        let (t4, f4) = &v[1];
        assert_eq!(
            (t4.best_min_distance, f4[0].attempt),
            (1.3, 1),
            "the best failing flight first"
        );
        assert_eq!(t4.trajectories, [PathBuf::from("c4_1.csv"), PathBuf::from("c4_0.csv")]);
        let (t1, _) = &v[2];
        assert!(t1.failure_rate_low < t1.failure_rate && t1.failure_rate < t1.failure_rate_high);
        // 1 of 3: failed once, not confirmed; settled either way.
        let one_of_three = [
            flight(5, 0, 1.0, 60.0),
            flight(5, 1, 2.0, 60.0),
            flight(5, 2, 2.0, 60.0),
        ];
        let v = verdicts(&one_of_three, 3);
        assert_eq!((v[0].0.confirmed, v[0].0.settled, v[0].0.failures), (false, true, 1));
        let cut = verdicts(&one_of_three[..1], 3);
        assert_eq!((cut[0].0.confirmed, cut[0].0.settled), (false, false), "pending");
        assert!(
            verdicts(&one_of_three[..1], 1)[0].0.confirmed,
            "K = 1: one failure confirms"
        );
    }

    #[test]
    fn one_flight_per_test_ranks_as_the_flights_do() {
        let records = [
            flight(1, 0, 1.2, 60.0),
            flight(2, 0, 0.8, 90.0),
            flight(3, 0, 0.8, 40.0),
        ];
        let v = verdicts(&records, 1);
        assert_eq!(v.iter().map(|(t, _)| t.candidate.0).collect::<Vec<_>>(), [3, 2, 1]);
        let single = test_score(&[0.8], &[40.0], 0);
        assert_eq!(v[0].0.test_score, single);
        assert_eq!(score_sum(v.iter().map(|(t, _)| t)), 0.0, "no obstacles, no score");
    }
}
