//! Confirmed failures (`generate --confirm K`): a test that fails is flown again, up to K flights in all, and
//! counts as failing only when most of its flights fail. On PX4 many flights end within centimetres of the
//! 1.5 m line, so one failing flight is close to a coin toss, and the organisers fly a submitted test again.
//!
//! A test stops being flown once the majority of K is settled (K = 3: two failures, or two passes). Only a
//! test that failed at least once is flown again; K = 1 is one flight per test, as without confirmation.

use crate::campaign::ground::candidate::CandidateId;
use std::collections::BTreeMap;

use crate::campaign::store::journal::FlightRecord;
use crate::model::competition::FAIL_BELOW_M;

/// Whether a flight failed: its judged minimum distance is below 1.5 m (no distance: it did not).
pub fn failed(min_distance: Option<f64>) -> bool {
    min_distance.is_some_and(|d| d < FAIL_BELOW_M)
}

/// One test's flights so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Tally {
    /// Flights that count towards the verdict.
    pub flights: usize,
    /// Of those, the failing ones.
    pub failures: usize,
    /// The number its next flight gets (one more than the highest journaled; 0 for a test not yet flown).
    pub next_attempt: u32,
}

impl Tally {
    /// The tally once `record` (a flight of this test) is added.
    pub fn with(self, record: &FlightRecord) -> Self {
        Self {
            flights: self.flights + 1,
            failures: self.failures + usize::from(failed(record.flown.min_distance)),
            next_attempt: self.next_attempt.max(record.attempt + 1),
        }
    }

    /// Whether the majority of `k` flights is settled either way.
    pub fn decided(&self, k: usize) -> bool {
        let passes = self.flights - self.failures;
        2 * self.failures > k || 2 * passes >= k
    }

    /// Whether more than half of `k` flights failed: the test is confirmed as failing. With `k` = 1, any
    /// failing flight.
    pub fn confirmed(&self, k: usize) -> bool {
        2 * self.failures > k
    }

    /// Whether the test is to be flown again: it failed at least once and the majority is not settled.
    pub fn wants_another(&self, k: usize) -> bool {
        self.failures > 0 && !self.decided(k)
    }
}

/// Each flown test's tally and its first flight, by candidate.
pub fn tallies(records: &[FlightRecord]) -> BTreeMap<CandidateId, (Tally, &FlightRecord)> {
    let mut out: BTreeMap<CandidateId, (Tally, &FlightRecord)> = BTreeMap::new();
    // An interrupted flight or a failed backend says nothing about the test.
    for r in records.iter().filter(|r| r.charged()) {
        let entry = out.entry(r.candidate).or_insert((Tally::default(), r));
        entry.0 = entry.0.with(r);
        if r.attempt < entry.1.attempt {
            entry.1 = r;
        }
    }
    out
}

/// The tests whose confirmation is not settled, in the order of their last journaled flight (the longest
/// waiting first), each with its tally and first flight.
pub fn pending(records: &[FlightRecord], k: usize) -> Vec<(Tally, &FlightRecord)> {
    let all = tallies(records);
    let mut last: Vec<(usize, CandidateId)> = Vec::new();
    for (i, r) in records.iter().enumerate() {
        last.retain(|(_, c)| *c != r.candidate);
        last.push((i, r.candidate));
    }
    last.iter()
        .filter_map(|(_, c)| all.get(c).copied())
        .filter(|(t, _)| t.wants_another(k))
        .collect()
}

/// Each test's first flight (attempt 0), in journal order: the flights the report's first-flight figures are
/// over, and the records [`as_learnt`] gives the campaign to learn from.
pub fn first_flights(records: &[FlightRecord]) -> Vec<FlightRecord> {
    records.iter().filter(|r| r.attempt == 0).cloned().collect()
}

/// Each test once, as the campaign learns from it: its first flight's record, in journal order, with the mean
/// distance of its charged flights. A repeat flight is evidence about its test, so a test its repeats refuted
/// stops counting as a failure (as a parent of children, an elite, a point of the flights' kernel); on PX4 the
/// repeats refute many first failures (docs/design-constants.md#confirmed-failures). Counted as separate
/// records instead, repeats would weigh the failing tests twice and, as copies, pull the failing tests'
/// diversity down. With one flight per test this is the journal itself.
pub fn as_learnt(records: &[FlightRecord]) -> Vec<FlightRecord> {
    let mut sums: BTreeMap<CandidateId, (f64, f64, usize)> = BTreeMap::new();
    for r in records.iter().filter(|r| r.charged()) {
        if let Some(d) = r.flown.min_distance {
            let e = sums.entry(r.candidate).or_default();
            *e = (e.0 + d, e.1 + r.flown.min_distance_raw.unwrap_or(d), e.2 + 1);
        }
    }
    first_flights(records)
        .into_iter()
        .map(|mut r| {
            if let Some(&(sum, raw, n)) = sums.get(&r.candidate).filter(|s| s.2 > 1) {
                r.flown.min_distance = Some(sum / n as f64);
                r.flown.min_distance_raw = Some(raw / n as f64);
            }
            r
        })
        .collect()
}

/// Of the tests flown again after failing their first flight, how many failed their second flight too, and
/// how many there are: the confirmation rate's numerator and denominator.
pub fn failed_again(records: &[FlightRecord]) -> (usize, usize) {
    let first_failed: BTreeMap<CandidateId, bool> = records
        .iter()
        .filter(|r| r.attempt == 0)
        .map(|r| (r.candidate, failed(r.flown.min_distance)))
        .collect();
    records
        .iter()
        .filter(|r| r.attempt == 1 && first_failed.get(&r.candidate) == Some(&true))
        .fold((0, 0), |(again, of), r| {
            (again + usize::from(failed(r.flown.min_distance)), of + 1)
        })
}

/// The trajectory of a test's flight, relative to the campaign folder: `flights/candidate_N.csv` for its
/// first, `candidate_N_2.csv` for its second, and so on.
pub fn trajectory_name(candidate: CandidateId, attempt: u32) -> std::path::PathBuf {
    let name = match attempt {
        0 => format!("candidate_{candidate}.csv"),
        a => format!("candidate_{candidate}_{}.csv", a + 1),
    };
    std::path::Path::new("flights").join(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::store::journal::test_record;

    fn flight(candidate: u64, attempt: u32, d: f64) -> FlightRecord {
        FlightRecord {
            attempt,
            ..test_record(candidate, 1.0, Some(d))
        }
    }

    #[test]
    fn the_campaign_learns_each_test_once_at_its_flights_mean() {
        let mut interrupted = flight(2, 2, 0.1);
        interrupted.flown.status = crate::campaign::ground::flight_status::FlightStatus::Interrupted;
        let records = vec![
            flight(1, 0, 1.3),
            flight(2, 0, 1.2),
            flight(3, 0, 2.0),
            flight(2, 1, 1.7),
            flight(1, 1, 1.4),
            flight(2, 2, 1.8),
            interrupted,
        ];
        let learnt = as_learnt(&records);
        let got: Vec<(u64, f64)> = learnt
            .iter()
            .map(|r| (r.candidate.0, r.flown.min_distance.unwrap_or(-1.0)))
            .collect();
        // Test 1 confirmed (mean 1.35 m); test 2 refuted (1.2, 1.7, 1.8: 1.567 m, the interrupted flight not
        // counted); test 3 flown once, unchanged.
        assert_eq!(got.len(), 3);
        assert_eq!((got[0].0, got[1].0, got[2].0), (1, 2, 3));
        assert!((got[0].1 - 1.35).abs() < 1e-12 && (got[1].1 - 4.7 / 3.0).abs() < 1e-12 && got[2].1 == 2.0);
        assert!(learnt.iter().all(|r| r.attempt == 0));
        let once: Vec<FlightRecord> = records[..3].to_vec();
        assert_eq!(as_learnt(&once), once, "one flight per test: the journal itself");
    }

    fn tally(outcomes: &str) -> Tally {
        (outcomes.bytes().enumerate()).fold(Tally::default(), |t, (i, o)| {
            t.with(&flight(0, i as u32, if o == b'F' { 1.0 } else { 2.0 }))
        })
    }

    #[test]
    fn the_majority_of_k_settles_a_test() {
        // (flights so far, K) -> (flown again?, confirmed?)
        let cases = [
            ("P", 3, false, false),
            ("F", 1, false, true),
            ("F", 2, true, false),
            ("FF", 2, false, true),
            ("FP", 2, false, false),
            ("F", 3, true, false),
            ("FF", 3, false, true),
            ("FP", 3, true, false),
            ("FPF", 3, false, true),
            ("FPP", 3, false, false),
            ("FFF", 4, false, true),
            ("FFP", 4, true, false),
            ("FFPF", 4, false, true),
            ("FPP", 4, false, false),
            ("FPFP", 4, false, false),
        ];
        for (outcomes, k, again, confirmed) in cases {
            let t = tally(outcomes);
            assert_eq!(
                (t.wants_another(k), t.confirmed(k)),
                (again, confirmed),
                "{outcomes} of K = {k}"
            );
            // Stopped tests: confirmed exactly when strictly more than half of their own flights failed.
            if !again {
                assert_eq!(confirmed, 2 * t.failures > t.flights);
            }
            assert!(t.flights <= k, "never more than K flights");
        }
        assert_eq!(tally("FPF").next_attempt, 3);
    }

    #[test]
    fn pending_tests_come_longest_waiting_first_with_their_next_attempt() {
        let records = [
            flight(7, 0, 1.0),
            flight(8, 0, 2.0),
            flight(9, 0, 1.2),
            flight(7, 1, 2.0),
            flight(10, 0, 1.0),
            flight(10, 1, 1.0),
        ];
        let p = pending(&records, 3);
        let got: Vec<(u64, u32, usize)> = p
            .iter()
            .map(|(t, first)| (first.candidate.0, t.next_attempt, t.failures))
            .collect();
        // 8 passed, 10 is confirmed (2 of 3); 9 waits longer than 7.
        assert_eq!(got, [(9, 1, 1), (7, 2, 1)]);
        assert!(pending(&records, 1).is_empty(), "K = 1 flies nothing again");
        assert_eq!(failed_again(&records), (1, 2));
        assert_eq!(first_flights(&records).len(), 4);
    }

    #[test]
    fn re_flights_have_their_own_trajectory() {
        assert_eq!(
            trajectory_name(CandidateId(12), 0),
            std::path::Path::new("flights/candidate_12.csv")
        );
        assert_eq!(
            trajectory_name(CandidateId(12), 1),
            std::path::Path::new("flights/candidate_12_2.csv")
        );
    }
}
