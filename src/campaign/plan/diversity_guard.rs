//! Which children of the failing flights may be drawn, and which candidates a round may fly. A candidate must
//! differ from the round's others by the campaign's near-duplicate rule (`--max-iou`). A child may come closer to
//! the flown tests, up to `--child-max-iou`, because near copies of a failure fail far more often than their
//! distant neighbours. What bounds them is the failing tests' diversity, the user's floor: every child drawn and
//! every candidate flown must leave the failing tests' *expected* diversity above it, counting the failures so
//! far, each close child as a failure and every other candidate as a failure at its arm's failure rate so far.
//! Without that, the failures cluster where the vehicle fails (docs/design-constants.md#close-children).
//!
//! The expectation is over the campaign's *final* failing tests: the failures still to come (the flights after
//! this round at the campaign's failure rate so far, overlapping everything like the flown tests, or like the
//! failing tests so far when those overlap more: [`projection`]) are counted too. So the rule holds from the
//! first failure on, lenient early (many failures to come dilute a close pair) and strict late, also on a stack
//! that fails rarely (docs/design-constants.md#the-expectation-holds-from-the-first-failure).

use crate::campaign::settings::CampaignSettings;
use crate::campaign::store::journal::FlightRecord;
use crate::geometry::{Footprint, union_iou};
use crate::judge::diversity;
use crate::model::Obstacle;

use crate::campaign::learn::refit::MIN_FAILING_FOR_DIVERSITY;
/// Expected diversity a child must leave above the user's floor: the expectation is over one round's children,
/// and the flights' failures scatter around it.
pub const DIVERSITY_MARGIN: f64 = 0.02;

/// How close to a flown test a child may come: `child_max_iou`, never below `max_iou`.
pub fn child_max_iou(cfg: &CampaignSettings) -> f64 {
    cfg.learning.child_max_iou.max(cfg.screening.max_iou)
}

fn prints(obstacles: &[Obstacle]) -> Vec<Footprint> {
    obstacles.iter().map(Obstacle::footprint).collect()
}

/// The rule for one round's children or flights: the flown tests, the failing ones (weighted by how likely they fail) with
/// their weighted pairwise IoU summed (so a child's effect on diversity costs one IoU per failure), and the
/// siblings drawn so far.
#[derive(Debug, Clone)]
pub struct DiversityGuard {
    flown: Vec<Vec<Footprint>>,
    /// The failing tests (weight 1), and the candidates admitted since (close ones 1, the others their arm's
    /// failure rate).
    failing: Vec<(Vec<Footprint>, f64)>,
    /// Sum over pairs of the product of their weights and IoU ...
    pair_sum: f64,
    /// ... and of their weights alone: the expected diversity is 1 - pair_sum / pair_weight.
    pair_weight: f64,
    /// Flown failures (no close child below [`MIN_FAILING_FOR_DIVERSITY`] of them; no check before the first).
    failures: usize,
    /// The failures expected after this round and their mean IoU with any test ([`Self::expecting`]).
    future: (f64, f64),
    siblings: Vec<Vec<Footprint>>,
    max_iou: f64,
    child_max_iou: f64,
    floor: f64,
    last_close: bool,
}

impl DiversityGuard {
    /// The rule after the flights in `done` (failing below `fail_m`).
    pub fn new(done: &[FlightRecord], fail_m: f64, (max_iou, child_max_iou): (f64, f64), floor: f64) -> Self {
        let mut rule = Self {
            flown: done.iter().map(|r| prints(&r.obstacles)).collect(),
            failing: Vec::new(),
            pair_sum: 0.0,
            pair_weight: 0.0,
            failures: 0,
            future: (0.0, 0.0),
            siblings: Vec::new(),
            max_iou,
            child_max_iou: child_max_iou.max(max_iou),
            floor,
            last_close: false,
        };
        for r in done.iter().filter(|r| r.flown.min_distance.is_some_and(|d| d < fail_m)) {
            let p = prints(&r.obstacles);
            let pairs = rule.pairs_with(&p, 1.0);
            rule.add(p, 1.0, pairs);
            rule.failures += 1;
        }
        rule
    }

    /// The rule for a round of campaign `cfg` after the flights in `done`, with `later` flights of the budget
    /// left after this round ([`projection`]).
    pub fn for_round(done: &[FlightRecord], fail_m: f64, cfg: &CampaignSettings, later: usize) -> Self {
        let (failures, mean_iou) = projection(done, fail_m, later);
        Self::new(
            done,
            fail_m,
            (cfg.screening.max_iou, child_max_iou(cfg)),
            cfg.learning.min_diversity,
        )
        .expecting(failures, mean_iou)
    }

    /// Counts `failures` more failing tests to come (after this round), each overlapping any other test by
    /// `mean_iou`: the expectation is then over the campaign's final failing tests. Called once, before any
    /// candidate is admitted.
    fn expecting(mut self, failures: f64, mean_iou: f64) -> Self {
        let (m, b) = (failures.max(0.0), mean_iou.clamp(0.0, 1.0));
        let known: f64 = self.failing.iter().map(|(_, w)| w).sum();
        // Pairs of the known with the future ones, and of the future ones among themselves (m^2 / 2).
        self.pair_sum += known * m * b + m * m / 2.0 * b;
        self.pair_weight += known * m + m * m / 2.0;
        self.future = (m, b);
        self
    }

    /// What joining the failing tests with weight `w` adds to (pair_sum, pair_weight).
    fn pairs_with(&self, p: &[Footprint], w: f64) -> (f64, f64) {
        let (m, b) = self.future;
        self.failing.iter().fold((w * m * b, w * m), |(s, n), (f, wf)| {
            (s + w * wf * union_iou(p, f), n + w * wf)
        })
    }

    fn add(&mut self, p: Vec<Footprint>, w: f64, (sum, weight): (f64, f64)) {
        self.pair_sum += sum;
        self.pair_weight += weight;
        self.failing.push((p, w));
    }

    /// Whether `child` (a candidate failing at `fail_rate`, or certainly if it is close to a flown test) may be
    /// drawn or flown; if so it joins the siblings and, weighted, the failing tests the next one is checked
    /// against.
    pub fn admit(&mut self, child: &[Obstacle], fail_rate: f64) -> bool {
        let p = prints(child);
        if self.siblings.iter().any(|s| union_iou(&p, s) > self.max_iou) {
            return false;
        }
        let closest = self.flown.iter().map(|f| union_iou(&p, f)).fold(0.0, f64::max);
        let close = closest > self.max_iou;
        // Below MIN_FAILING_FOR_DIVERSITY failures diversity says too little to risk a close child; before the
        // first failure there is nothing to keep diverse.
        let counted = self.failures + 1 >= MIN_FAILING_FOR_DIVERSITY;
        if close && (closest > self.child_max_iou || !counted) {
            return false;
        }
        let w = if close { 1.0 } else { fail_rate.clamp(0.0, 1.0) };
        let (sum, weight) = self.pairs_with(&p, w);
        let expected = 1.0 - (self.pair_sum + sum) / (self.pair_weight + weight).max(f64::MIN_POSITIVE);
        // Below the floor, a candidate that does not lower the expectation is still flown: refusing it too would
        // leave the rest of the budget unflown (on mission 2 seed 2, half of a budget of 100).
        let now = 1.0 - self.pair_sum / self.pair_weight.max(f64::MIN_POSITIVE);
        if self.failures > 0 && expected < self.floor + DIVERSITY_MARGIN && (close || expected < now) {
            return false;
        }
        self.add(p.clone(), w, (sum, weight));
        self.last_close = close;
        self.siblings.push(p);
        true
    }

    /// Whether a child may come closer to a flown test than `max_iou` at all: from
    /// [`MIN_FAILING_FOR_DIVERSITY`] - 1 failures on (the child would make the count), and only with a
    /// `child_max_iou` above `max_iou`.
    pub fn close_children_may_fly(&self) -> bool {
        self.failures + 1 >= MIN_FAILING_FOR_DIVERSITY && self.child_max_iou > self.max_iou
    }

    /// Whether the child admitted last overlaps a flown test beyond `max_iou`.
    pub fn last_was_close(&self) -> bool {
        self.last_close
    }
}

/// The failing tests still to come: those of `later` flights at the failure rate of `done` so far (failing
/// below `fail_m`), and their mean IoU with any other test. That is the flown tests' mean pairwise IoU, or from
/// [`MIN_FAILING_FOR_DIVERSITY`] failing tests on the failing tests' own if higher: the failures to come cluster
/// like those so far (docs/design-constants.md#failures-to-come).
pub fn projection(done: &[FlightRecord], fail_m: f64, later: usize) -> (f64, f64) {
    let distances: Vec<f64> = done.iter().filter_map(|r| r.flown.min_distance).collect();
    let failing: Vec<Vec<Obstacle>> = done
        .iter()
        .filter(|r| r.flown.min_distance.is_some_and(|d| d < fail_m))
        .map(|r| r.obstacles.clone())
        .collect();
    let rate = if distances.is_empty() {
        0.0
    } else {
        failing.len() as f64 / distances.len() as f64
    };
    let flown: Vec<Vec<Obstacle>> = done.iter().map(|r| r.obstacles.clone()).collect();
    let mut mean_iou = diversity(&flown).map_or(0.0, |d| 1.0 - d);
    if failing.len() >= MIN_FAILING_FOR_DIVERSITY {
        mean_iou = mean_iou.max(diversity(&failing).map_or(0.0, |d| 1.0 - d));
    }
    (rate * later as f64, mean_iou)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::store::journal::test_record;

    fn at(x: f64) -> Vec<Obstacle> {
        vec![Obstacle::new(4.0, 4.0, 10.0, x, 10.0, 0.0)]
    }

    fn flown(x: f64, d: f64) -> FlightRecord {
        let mut r = test_record(0, 1.0, Some(d));
        r.obstacles = at(x);
        r
    }

    #[test]
    fn without_room_above_max_iou_only_distinct_children_pass() {
        let done = [flown(0.0, 1.0), flown(20.0, 2.0)];
        // Many distinct failures to come, so diversity does not bind here.
        let mut rule = DiversityGuard::new(&done, 1.5, (0.5, 0.5), 0.8).expecting(50.0, 0.0);
        // Shifted by 1 m of 4: IoU 3/5 = 0.6 with the first flight.
        assert!(!rule.admit(&at(1.0), 0.3));
        // Shifted by 2 m: IoU 2/6.
        assert!(rule.admit(&at(2.0), 0.3));
        // A sibling of that one by IoU 0.6: refused.
        assert!(!rule.admit(&at(3.0), 0.3));
        assert!(rule.admit(&at(40.0), 0.3));
    }

    #[test]
    fn a_close_child_needs_enough_diverse_failures() {
        // One failure: diversity says too little, so no close child yet.
        let mut rule = DiversityGuard::new(&[flown(0.0, 1.0)], 1.5, (0.5, 0.75), 0.8);
        assert!(!rule.admit(&at(1.0), 0.3));
        // Ten failures 20 m apart: a child at IoU 0.6 of one leaves diversity 1 - 0.6 / 55 > 0.82.
        let spread: Vec<FlightRecord> = (0..10).map(|i| flown(20.0 * f64::from(i), 1.0)).collect();
        let mut rule = DiversityGuard::new(&spread, 1.5, (0.5, 0.75), 0.8);
        assert!(rule.admit(&at(1.0), 0.3) && rule.last_was_close());
        assert!(rule.admit(&at(10.0), 0.3) && !rule.last_was_close());
        // Beyond child_max_iou: IoU 3.5/4.5 = 0.78.
        assert!(!rule.admit(&at(20.5), 0.3));
        // Near a flight that passed, the same rule applies (it is close to a flown test).
        assert!(!DiversityGuard::new(&[flown(0.0, 2.0)], 1.5, (0.5, 0.75), 0.8).admit(&at(1.0), 0.3));
    }

    #[test]
    fn the_failures_to_come_dilute_a_pair_early_and_not_late() {
        // One failure at 0; a child at 2 overlaps it by IoU 8 / 24 = 1/3, failing at 0.3.
        let done = [flown(0.0, 1.0), flown(20.0, 2.0)];
        let rule = |future: f64| DiversityGuard::new(&done, 1.5, (0.5, 0.75), 0.8).expecting(future, 0.05);
        // In the last round no failure is to come: the pair alone leaves 1 - 1/3 = 0.67 < 0.8.
        assert!(!rule(0.0).admit(&at(2.0), 0.3));
        // Ten failures to come at IoU 0.05: 1 - (0.5 + 2.5 + 0.1 + 0.15) / (10 + 50 + 0.3 + 3) = 0.949.
        assert!(rule(10.0).admit(&at(2.0), 0.3));
        // A distinct candidate flies either way, and before any failure nothing is checked.
        assert!(rule(0.0).admit(&at(40.0), 0.3));
        assert!(
            DiversityGuard::new(&[flown(0.0, 2.0)], 1.5, (0.5, 0.75), 0.8)
                .expecting(0.0, 0.05)
                .admit(&at(2.0), 0.3)
        );
        // Two failures 40 m apart, no failure to come: a candidate failing at 0.5 at IoU 1/3 of one leaves
        // 1 - (0.5 / 3) / 2 = 0.917: the rule binds below 4 failures too.
        let two = [flown(0.0, 1.0), flown(40.0, 1.0)];
        let last = |floor: f64| DiversityGuard::new(&two, 1.5, (0.5, 0.75), floor);
        assert!(last(0.8).admit(&at(-2.0), 0.5));
        assert!(!last(0.9).admit(&at(-2.0), 0.5));
    }

    #[test]
    fn the_projection_is_the_failure_rate_over_the_flights_left_and_the_flown_mean_iou() {
        assert_eq!(projection(&[], 1.5, 40), (0.0, 0.0), "no flight, no rate");
        // 1 of 4 flights failed (one not landed does not count); tests at 0, 2 (IoU 1/3 of 0), 40 and 80.
        let mut done = vec![flown(0.0, 1.0), flown(2.0, 2.0), flown(40.0, 2.0), flown(80.0, 3.0)];
        let mut lost = flown(120.0, 1.0);
        lost.flown.min_distance = None;
        done.push(lost);
        let (failures, mean_iou) = projection(&done, 1.5, 40);
        assert!((failures - 10.0).abs() < 1e-12, "{failures}");
        // One pair of 10 overlaps, by 1/3.
        assert!((mean_iou - 1.0 / 30.0).abs() < 1e-12, "{mean_iou}");
        // Four failures that overlap more than the flights do: theirs counts. At 0, 2, 40 and 42, 2 of 6 pairs
        // overlap by 1/3; with 4 flights more far away, 2 of 28.
        let mut done = vec![flown(0.0, 1.0), flown(2.0, 1.0), flown(40.0, 1.0), flown(42.0, 1.0)];
        done.extend((0..4).map(|i| flown(100.0 + 20.0 * f64::from(i), 2.0)));
        let (failures, mean_iou) = projection(&done, 1.5, 10);
        assert!((failures - 5.0).abs() < 1e-12, "{failures}");
        assert!((mean_iou - 1.0 / 9.0).abs() < 1e-12, "{mean_iou}");
        // Three of them: too few to say, the flights' mean holds (1 of 21 pairs).
        done.remove(3);
        let (_, mean_iou) = projection(&done, 1.5, 10);
        assert!((mean_iou - 1.0 / 63.0).abs() < 1e-12, "{mean_iou}");
    }

    #[test]
    fn close_children_stop_when_the_floor_would_break() {
        // Four failures, two of them overlapping by IoU 0.6: diversity 1 - 0.6 / 6 = 0.9.
        let done = [flown(0.0, 1.0), flown(1.0, 1.0), flown(40.0, 1.0), flown(80.0, 1.0)];
        let admitted = |floor: f64| {
            let mut rule = DiversityGuard::new(&done, 1.5, (0.5, 0.75), floor);
            [41.0, 81.0, 121.0, 39.0, 79.0]
                .iter()
                .filter(|&&x| rule.admit(&at(x), 0.3))
                .copied()
                .collect::<Vec<f64>>()
        };
        // A close child counts as a failure, the others as 0.3 of one: 41 leaves 1 - 1.2 / 10 = 0.88, 81 then
        // 1 - 1.8 / 15 = 0.88, the distant 121 1 - 1.8 / 16.8 = 0.893, 39 (0.6 of 40, 1/3 of 41) 0.882, 79 0.879.
        assert_eq!(admitted(0.8), vec![41.0, 81.0, 121.0, 39.0, 79.0]);
        // Without 41 and 81, 39 and 79 are no siblings: 39 leaves 1 - 1.2 / 11.5 = 0.896, then 79 0.893.
        assert_eq!(admitted(0.87), vec![121.0, 39.0, 79.0], "0.88 < 0.87 + margin");
        assert_eq!(admitted(0.875), vec![121.0, 39.0], "0.893 < 0.875 + margin");
        assert_eq!(
            admitted(0.9),
            vec![121.0],
            "121 leaves 0.917 < 0.92, but raises it from 0.9"
        );
        // A child that is not close still counts: at -2 it overlaps the failures at 0 and 1 by 1/3 and 1/7,
        // which at weight 0.3 leaves 1 - (0.6 + 0.143) / 7.2 = 0.897.
        let child = at(-2.0);
        assert!(DiversityGuard::new(&done, 1.5, (0.5, 0.75), 0.87).admit(&child, 0.3));
        let mut rule = DiversityGuard::new(&done, 1.5, (0.5, 0.75), 0.88);
        assert!(!rule.admit(&child, 0.3) && !rule.last_was_close());
    }

    #[test]
    fn below_the_floor_only_candidates_that_do_not_lower_the_diversity_fly() {
        // Four failures, two overlapping by IoU 0.6: diversity 1 - 0.6 / 6 = 0.9, below the floor 0.9 + margin.
        let done = [flown(0.0, 1.0), flown(1.0, 1.0), flown(40.0, 1.0), flown(80.0, 1.0)];
        let mut rule = DiversityGuard::new(&done, 1.5, (0.5, 0.75), 0.9);
        // Overlapping 0 and 1 by 1/3 and 1/7: 1 - (0.6 + 0.143) / 7.2 = 0.897, lower: refused.
        assert!(!rule.admit(&at(-2.0), 0.3));
        // Far from every failure: 0.917, higher, so it flies; so does the next one, far from it too.
        assert!(rule.admit(&at(120.0), 0.3));
        assert!(rule.admit(&at(160.0), 0.3));
        // A close child: refused.
        assert!(!rule.admit(&at(81.0), 0.3));
        // A candidate that cannot fail changes nothing.
        assert!(rule.admit(&at(-3.0), 0.0));
    }
}
