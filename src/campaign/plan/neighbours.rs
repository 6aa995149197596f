//! Neighbour proposals of the adapted generator: part of each round's candidates are drawn in small boxes of
//! draw space around the campaign's failing flights so far (its *parents*), where the next failures are
//! likeliest (a failure says much about its neighbours, a near miss little:
//! docs/design-constants.md#drawing-around-failures); before the first failure, around its closest near misses.
//! They come on top of the round's candidates from the histogram distribution ([`crate::generator::adaptive`]),
//! which keep the campaign exploring. Children are drawn distinct from each other and from the flown tests, or
//! close to a flown test where the failing tests' diversity allows ([`crate::campaign::plan::diversity_guard`]);
//! the near-duplicate filter would drop most of them before flight otherwise.

use crate::campaign::ground::candidate::{Candidate, CandidateId, LfsPrediction, Lineage};
use crate::campaign::learn::failure_counts::BinCount;
use crate::campaign::plan::diversity_guard::{DiversityGuard, child_max_iou};
use crate::campaign::plan::rank::{Seen, rank_unflown, rank_unflown_within};
use crate::campaign::settings::CampaignSettings;
use crate::campaign::store::journal::FlightRecord;
use crate::generator::adaptive::{DIMS, Neighbourhood};

/// Candidates drawn around the parents per round (at most; no more than the round's own draws), shared out
/// among them in turn.
pub const CHILDREN: usize = 36;
/// Parents per round: the most severe failing flights so far.
pub const PARENTS: usize = 12;
/// Half the side of a parent's box, in unit draws (15 % of each range either side).
pub const HALF_WIDTH: f64 = 0.15;
/// Half the side of a parent's narrow box, in unit draws: once close children may fly, every second pass over
/// the parents draws there ([`child_box`]), since the closer a flight is to a failure the likelier it fails and
/// few draws of the wide box come that close (docs/design-constants.md#narrow-box).
pub const NARROW_HALF_WIDTH: f64 = 0.05;

/// Valid draws a parent's box may offer for one child before it gives way to the histogram.
pub const CHILD_TRIES: u32 = 64;

/// Bounds of the share of a round's flights given to neighbour candidates: never all (the histogram still
/// explores), never none (their rate is still measured).
pub const LOCAL_FLIGHT_SHARE: (f64, f64) = (0.25, 0.85);

/// Flights within this margin of the failure distance stand in as parents while the campaign has no failure
/// yet, metres: on a stack that rarely fails they are all it knows (docs/design-constants.md#near-miss-parents).
pub const NEAR_MISS_M: f64 = 0.3;
/// Near-miss parents per round at most (the closest), so their children crowd the closest flights.
pub const NEAR_MISS_PARENTS: usize = 4;
/// Share of a round's flights offered to a near miss's children: fixed at the floor of [`LOCAL_FLIGHT_SHARE`],
/// as they fail little more often than the histogram's (docs/design-constants.md#near-miss-flight-share).
pub const NEAR_MISS_FLIGHT_SHARE: f64 = LOCAL_FLIGHT_SHARE.0;

/// The neighbourhoods of the failing flights in `done` (flown closer than `fail_m`; at most [`PARENTS`],
/// closest first, ties by candidate); with no failure, of the closest near misses (below `fail_m` +
/// [`NEAR_MISS_M`], at most [`NEAR_MISS_PARENTS`]). Flights of candidates this run did not draw are skipped.
pub fn parents(
    done: &[FlightRecord],
    unit_of: impl Fn(CandidateId) -> Option<[f64; DIMS]>,
    fail_m: f64,
) -> (Vec<Neighbourhood>, Lineage) {
    let mut flown: Vec<(f64, CandidateId, [f64; DIMS])> = done
        .iter()
        .filter_map(|r| Some((r.flown.min_distance?, r.candidate, unit_of(r.candidate)?)))
        .filter(|(d, _, _)| *d < fail_m + NEAR_MISS_M)
        .collect();
    flown.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let failures = flown.iter().take_while(|(d, _, _)| *d < fail_m).count();
    let (lineage, take) = if failures > 0 {
        (Lineage::Failures, failures.min(PARENTS))
    } else {
        (Lineage::NearMisses, flown.len().min(NEAR_MISS_PARENTS))
    };
    let boxes = flown[..take]
        .iter()
        .map(|(_, _, centre)| Neighbourhood {
            centre: *centre,
            half_width: HALF_WIDTH,
        })
        .collect();
    (boxes, lineage)
}

/// The box a round's child `j` is drawn in, among `parents`' boxes: the parents in turn, in their wide box on
/// the first pass, then (with `close`: close children may fly) narrow and wide passes alternately. Without
/// close children every pass is wide: the narrow box's draws overlap their parent by more than `--max-iou`.
pub fn child_box(parents: &[Neighbourhood], j: usize, close: bool) -> Option<Neighbourhood> {
    let parent = parents.get(j.checked_rem(parents.len())?)?;
    let narrow = close && (j / parents.len()) % 2 == 1;
    Some(Neighbourhood {
        half_width: if narrow { NARROW_HALF_WIDTH } else { parent.half_width },
        ..*parent
    })
}

/// Share of a round's flights for neighbour candidates: their failure rate so far over the sum of theirs and
/// the histogram's (Laplace-smoothed, so 0.5 before any flight), within [`LOCAL_FLIGHT_SHARE`]. The arm that
/// finds failures gets the flights; on a stack where neighbours fail no more often, the split stays even.
pub fn local_flight_share(local: BinCount, histogram: BinCount) -> f64 {
    let (l, h) = (local.rate(), histogram.rate());
    (l / (l + h)).clamp(LOCAL_FLIGHT_SHARE.0, LOCAL_FLIGHT_SHARE.1)
}

/// The round's flights: the best `share` of `remaining` among the neighbour candidates (`is_local`), the rest
/// from all others, then neighbours again if the others run out; near-duplicates of any flown test skipped (for
/// neighbours, beyond `--child-max-iou`), and
/// each flight admitted by `guard` (distinct from the round's others, keeping the failing tests' expected
/// diversity) with its arm's failure rate (`rates`: neighbours, others).
pub fn rank_split(
    fresh: &[LfsPrediction],
    is_local: impl Fn(CandidateId) -> bool,
    share: f64,
    (seen, candidates): (&Seen, &[Candidate]),
    cfg: &CampaignSettings,
    remaining: usize,
    (guard, (near_rate, other_rate)): (&mut DiversityGuard, (f64, f64)),
) -> Vec<LfsPrediction> {
    let (near, other): (Vec<LfsPrediction>, Vec<LfsPrediction>) =
        fresh.iter().cloned().partition(|s| is_local(s.candidate));
    let quota = ((remaining as f64 * share).round() as usize).min(remaining);
    let near = rank_unflown_within(&near, seen, candidates, cfg, usize::MAX, child_max_iou(cfg));
    let mut chosen: Vec<LfsPrediction> = Vec::new();
    let mut later = Vec::new();
    for s in near {
        if chosen.len() < quota && guard.admit(&candidates[s.candidate.index()].obstacles, near_rate) {
            chosen.push(s);
        } else {
            later.push(s);
        }
    }
    let others = rank_unflown(&other, seen, candidates, cfg, usize::MAX);
    let rest = others
        .into_iter()
        .map(|s| (s, other_rate))
        .chain(later.into_iter().map(|s| (s, near_rate)));
    for (s, rate) in rest {
        if chosen.len() >= remaining {
            break;
        }
        if chosen.iter().all(|c| c.candidate != s.candidate)
            && guard.admit(&candidates[s.candidate.index()].obstacles, rate)
        {
            chosen.push(s);
        }
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(candidate: u64, flown: Option<f64>) -> FlightRecord {
        crate::campaign::store::journal::test_record(candidate, 1.0, flown)
    }

    fn at(units: &[[f64; DIMS]]) -> impl Fn(CandidateId) -> Option<[f64; DIMS]> + '_ {
        |c| units.get(c.index()).copied()
    }

    #[test]
    fn the_failing_flights_are_the_parents() {
        let units: Vec<[f64; DIMS]> = (0..20).map(|i| [i as f64 / 20.0; DIMS]).collect();
        // Candidates 0-15 flew 1.0, 1.05, ... 1.75 m: 0-9 failed.
        let mut done: Vec<FlightRecord> = (0..16).map(|i| record(i, Some(1.0 + i as f64 * 0.05))).collect();
        done.push(record(16, None));
        done.push(record(42, Some(0.1)));
        let (p, lineage) = parents(&done, at(&units), 1.5);
        assert_eq!(lineage, Lineage::Failures);
        assert_eq!(
            p.len(),
            10,
            "only failures are parents while there are any; 42 is not this run's; 16 has no distance"
        );
        assert_eq!(p[0].centre, units[0]);
        assert_eq!(p[9].centre, units[9]);
        assert!(p.iter().all(|n| n.half_width == HALF_WIDTH));
        // More failures than PARENTS: the closest.
        let many: Vec<FlightRecord> = (0..20).map(|i| record(i, Some(1.4 - i as f64 * 0.01))).collect();
        let (p, _) = parents(&many, at(&units), 1.5);
        assert_eq!(p.len(), PARENTS);
        assert_eq!(p[0].centre, units[19]);
        assert!(parents(&[], at(&units), 1.5).0.is_empty());
    }

    #[test]
    fn with_no_failure_the_closest_near_misses_are_the_parents() {
        let units: Vec<[f64; DIMS]> = (0..20).map(|i| [i as f64 / 20.0; DIMS]).collect();
        // Candidates 0-15 flew 1.5, 1.55, ... 2.25 m: none failed; 0-5 are within 0.3 m of failing.
        let done: Vec<FlightRecord> = (0..16).rev().map(|i| record(i, Some(1.5 + i as f64 * 0.05))).collect();
        let (p, lineage) = parents(&done, at(&units), 1.5);
        assert_eq!(lineage, Lineage::NearMisses);
        assert_eq!(p.len(), NEAR_MISS_PARENTS);
        let centres: Vec<_> = p.iter().map(|n| n.centre).collect();
        assert_eq!(centres, vec![units[0], units[1], units[2], units[3]], "closest first");
        // Only two near misses (1.75 and 1.78 m); 1.85 m is not one.
        let few = vec![
            record(3, Some(1.85)),
            record(7, Some(1.78)),
            record(9, Some(1.75)),
            record(1, Some(2.5)),
        ];
        let (p, lineage) = parents(&few, at(&units), 1.5);
        assert_eq!(lineage, Lineage::NearMisses);
        assert_eq!(p.iter().map(|n| n.centre).collect::<Vec<_>>(), vec![units[9], units[7]]);
        // One failure takes over from every near miss.
        let mut one = few.clone();
        one.push(record(12, Some(1.49)));
        let (p, lineage) = parents(&one, at(&units), 1.5);
        assert_eq!((p.len(), lineage), (1, Lineage::Failures));
        assert_eq!(p[0].centre, units[12]);
        // Far flights only: no parent.
        assert!(parents(&few[3..], at(&units), 1.5).0.is_empty());
    }

    #[test]
    fn children_take_the_parents_in_turn_wide_then_narrow_when_close_children_may_fly() {
        let parent = |x: f64| Neighbourhood {
            centre: [x; DIMS],
            half_width: HALF_WIDTH,
        };
        let parents = [parent(0.2), parent(0.6)];
        let boxes = |close| -> Vec<(f64, f64)> {
            (0..6)
                .filter_map(|j| child_box(&parents, j, close))
                .map(|b| (b.centre[0], b.half_width))
                .collect()
        };
        let (w, n) = (HALF_WIDTH, NARROW_HALF_WIDTH);
        assert_eq!(
            boxes(true),
            vec![(0.2, w), (0.6, w), (0.2, n), (0.6, n), (0.2, w), (0.6, w)]
        );
        assert_eq!(
            boxes(false),
            vec![(0.2, w), (0.6, w), (0.2, w), (0.6, w), (0.2, w), (0.6, w)]
        );
        assert_eq!(child_box(&[], 3, true), None, "no parent, no box");
    }

    #[test]
    fn the_arm_that_fails_more_gets_more_flights() {
        let c = |flights, failures| BinCount { flights, failures };
        assert_eq!(local_flight_share(c(0, 0), c(0, 0)), 0.5);
        // 5 of 18 against 4 of 82: (6/20) / (6/20 + 5/84) = 0.834.
        assert!((local_flight_share(c(18, 5), c(82, 4)) - 0.8344).abs() < 1e-3);
        assert_eq!(local_flight_share(c(40, 20), c(40, 0)), LOCAL_FLIGHT_SHARE.1);
        assert_eq!(local_flight_share(c(40, 0), c(40, 20)), LOCAL_FLIGHT_SHARE.0);
    }
}
