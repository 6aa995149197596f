//! Where a learning campaign's flights failed (a diagnostic): flights and failures per bin of each generator draw, for the
//! report and `learnt.json` (a diagnostic; the campaign does not rank or draw by it).
//!
//! Why only a diagnostic: a per-bin rate learnt from a campaign's few failures is mostly noise, and ranking or
//! drawing by it found no more failing tests than static screening
//! (docs/design-constants.md#failure-counts-are-only-a-diagnostic). It still shows a user where their stack failed.

use serde::{Deserialize, Serialize};

use crate::campaign::ground::candidate::{Candidate, CandidateId, unit_of};
use crate::campaign::store::journal::FlightRecord;
use crate::generator::adaptive::{DIMS, bin_of};
use crate::model::competition::FAIL_BELOW_M;

/// Bins per draw (coarser than the generator's distribution: a campaign sees few failures).
pub const FAIL_BINS: usize = 5;

/// Flights and failures in one bin.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct BinCount {
    /// Flights whose draw fell in the bin.
    pub flights: u32,
    /// Of them, flights below 1.5 m.
    pub failures: u32,
}

impl BinCount {
    /// The failure rate, Laplace-smoothed (0.5 before any flight).
    pub fn rate(self) -> f64 {
        (f64::from(self.failures) + 1.0) / (f64::from(self.flights) + 2.0)
    }
}

/// Failure counts per bin of each draw.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct FailureCounts {
    /// `draws[d][k]`: flights whose draw `d` (a unit number) fell in `[k / FAIL_BINS, (k + 1) / FAIL_BINS)`
    /// (files with only the paper's five draws are padded with empty counts).
    #[serde(deserialize_with = "padded_counts")]
    pub draws: [[BinCount; FAIL_BINS]; DIMS],
    /// All flights.
    pub total: BinCount,
}

fn padded_counts<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[[BinCount; FAIL_BINS]; DIMS], D::Error> {
    crate::generator::adaptive::padded(d, [BinCount::default(); FAIL_BINS])
}

impl FailureCounts {
    /// Counts one flight: its generator draws and whether it failed.
    pub fn observe(&mut self, unit: &[f64; DIMS], failed: bool) {
        let f = u32::from(failed);
        let add = |c: &mut BinCount| {
            c.flights += 1;
            c.failures += f;
        };
        for (d, u) in unit.iter().enumerate() {
            add(&mut self.draws[d][bin_of(*u, FAIL_BINS)]);
        }
        add(&mut self.total);
    }
}

/// Flights and failures of the candidates `is_arm` picks and of the others (flights of candidates this run did
/// not draw count as others).
pub fn arm_counts(done: &[FlightRecord], is_arm: impl Fn(CandidateId) -> bool) -> (BinCount, BinCount) {
    let (mut near, mut other) = (BinCount::default(), BinCount::default());
    for r in done {
        if let Some(d) = r.flown.min_distance {
            let arm = if is_arm(r.candidate) { &mut near } else { &mut other };
            arm.flights += 1;
            arm.failures += u32::from(d < FAIL_BELOW_M);
        }
    }
    (near, other)
}

/// Where the journaled flights failed, per draw bin (flights of candidates this run did not draw, e.g. from a
/// longer resumed run, are skipped).
pub fn counted_failures(done: &[FlightRecord], candidates: &[Candidate]) -> FailureCounts {
    let mut m = FailureCounts::default();
    for r in done {
        if let (Some(u), Some(flown)) = (unit_of(candidates, r.candidate), r.flown.min_distance) {
            m.observe(&u, flown < FAIL_BELOW_M);
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn failures_are_counted_in_their_draws_bins() {
        let mut m = FailureCounts::default();
        m.observe(&[0.0, 0.19, 0.2, 0.99, 1.0, 0.5, 0.6, 0.0], true);
        m.observe(&[0.5; DIMS], false);
        assert_eq!(
            m.total,
            BinCount {
                flights: 2,
                failures: 1
            }
        );
        assert_eq!(
            m.draws[0][0],
            BinCount {
                flights: 1,
                failures: 1
            }
        );
        assert_eq!(m.draws[1][0].failures, 1);
        assert_eq!(m.draws[2][1].failures, 1);
        assert_eq!(m.draws[3][4].failures, 1);
        assert_eq!(m.draws[4][4].failures, 1, "1.0 belongs to the last bin");
        assert_eq!(m.draws[6][3].failures, 1, "a third obstacle starts the fourth fifth");
        assert_eq!(
            m.draws[2][2],
            BinCount {
                flights: 1,
                failures: 0
            }
        );
    }

    proptest! {
        #[test]
        fn every_draw_counts_every_flight(
            flights in proptest::collection::vec((proptest::array::uniform8(0.0f64..=1.0), any::<bool>()), 0..60)
        ) {
            let mut m = FailureCounts::default();
            for (u, f) in &flights {
                m.observe(u, *f);
            }
            for row in &m.draws {
                prop_assert_eq!(row.iter().map(|c| c.flights).sum::<u32>(), flights.len() as u32);
                prop_assert_eq!(row.iter().map(|c| c.failures).sum::<u32>(), m.total.failures);
            }
        }
    }
}
