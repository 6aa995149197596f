//! Collision Prevention per test: on how many of its flights the vehicle came inside `CP_DIST` and below the
//! competition's 1.5 m, and the closest its centre came, for every test flown with a Collision Prevention
//! verdict (a test need not fail the competition's threshold to break `CP_DIST`).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::Serialize;

use crate::campaign::fly::confirm::failed;
use crate::campaign::ground::candidate::CandidateId;
use crate::campaign::store::journal::FlightRecord;

/// One test's Collision Prevention verdict over its flights.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CpTest {
    /// The candidate.
    pub candidate: CandidateId,
    /// Its flights with a Collision Prevention verdict.
    pub flights: usize,
    /// Those that came inside `CP_DIST`.
    pub inside_cp_dist: usize,
    /// Those flown below the competition's threshold (1.5 m).
    pub below_threshold: usize,
    /// The closest the vehicle's centre came to a box over its flights, metres.
    pub closest_centre_m: Option<f64>,
}

/// Every test of `records` with a Collision Prevention verdict, the most flights inside `CP_DIST` first, then
/// the closest centre; empty in the other modes.
pub fn cp_tests(records: &[FlightRecord]) -> Vec<CpTest> {
    let mut by_test: BTreeMap<CandidateId, CpTest> = BTreeMap::new();
    for r in records.iter().filter(|r| r.flown.inside_cp_dist.is_some()) {
        let t = by_test.entry(r.candidate).or_insert(CpTest {
            candidate: r.candidate,
            flights: 0,
            inside_cp_dist: 0,
            below_threshold: 0,
            closest_centre_m: None,
        });
        t.flights += 1;
        t.inside_cp_dist += usize::from(r.flown.inside_cp_dist == Some(true));
        t.below_threshold += usize::from(failed(r.flown.min_distance));
        if let Some(c) = r.flown.closest_centre_m.filter(|c| c.is_finite()) {
            t.closest_centre_m = Some(t.closest_centre_m.map_or(c, |m| m.min(c)));
        }
    }
    let mut out: Vec<CpTest> = by_test.into_values().collect();
    out.sort_by(|a, b| {
        (b.inside_cp_dist.cmp(&a.inside_cp_dist)).then_with(|| {
            let key = |t: &CpTest| t.closest_centre_m.unwrap_or(f64::INFINITY);
            key(a).total_cmp(&key(b))
        })
    });
    out
}

/// The report.md section: a line of totals and a row per test (nothing outside Collision Prevention).
pub fn markdown(md: &mut String, tests: &[CpTest]) {
    if tests.is_empty() {
        return;
    }
    let inside = tests.iter().filter(|t| t.inside_cp_dist > 0).count();
    let below = tests.iter().filter(|t| t.below_threshold > 0).count();
    let _ = writeln!(
        md,
        "## Collision Prevention\n\n{inside} of {} tests came inside CP_DIST on at least one flight, {below} below \
         1.5 m. Closest centre: the closest the vehicle's centre came to a box, as Collision Prevention \
         measures.\n\n| candidate | flights | inside CP_DIST | below 1.5 m | closest centre m |\n|---|---|---|---|---|",
        tests.len()
    );
    for t in tests {
        let centre = t.closest_centre_m.map_or("n/a".into(), |c| format!("{c:.3}"));
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {centre} |",
            t.candidate, t.flights, t.inside_cp_dist, t.below_threshold
        );
    }
    md.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::store::journal::test_record;

    fn cp_flight(candidate: u64, d: f64, centre: f64) -> FlightRecord {
        let mut r = test_record(candidate, 1.0, Some(d));
        (r.flown.closest_centre_m, r.flown.inside_cp_dist) = (Some(centre), Some(centre < 2.0));
        r
    }

    #[test]
    fn counts_each_tests_flights_inside_cp_dist_and_below_the_threshold() {
        let records = [
            cp_flight(1, 2.4, 2.5),
            cp_flight(2, 1.3, 1.4),
            cp_flight(1, 1.8, 1.9),
            cp_flight(2, 1.6, 1.7),
            test_record(3, 1.0, Some(0.5)),
        ];
        let t = cp_tests(&records);
        assert_eq!(t.len(), 2, "a flight without a verdict is not a CP test: {t:?}");
        assert_eq!(
            (t[0].candidate, t[0].flights, t[0].inside_cp_dist, t[0].below_threshold),
            (CandidateId(2), 2, 2, 1)
        );
        assert_eq!(t[0].closest_centre_m, Some(1.4));
        assert_eq!(
            (t[1].candidate, t[1].inside_cp_dist, t[1].below_threshold),
            (CandidateId(1), 1, 0)
        );
        let mut md = String::new();
        markdown(&mut md, &t);
        assert!(
            md.contains("2 of 2 tests came inside CP_DIST on at least one flight, 1 below 1.5 m"),
            "{md}"
        );
        assert!(md.contains("| 2 | 2 | 2 | 1 | 1.400 |"), "{md}");
        let mut none = String::new();
        markdown(&mut none, &cp_tests(&records[4..]));
        assert!(none.is_empty());
    }
}
