//! Ranking screened candidates: the most expected competition points per minute of flight first (from the
//! LFS ensemble), else the most severe point prediction first; near-duplicates of each other and of the flown
//! tests skipped.

pub use crate::campaign::ground::candidate::LfsPrediction;
use crate::campaign::ground::candidate::{Candidate, CandidateId};
use crate::campaign::settings::CampaignSettings;

use crate::geometry::{Footprint, union_iou};
use crate::model::Obstacle;

/// Orders candidates with an ensemble by expected points per minute (most first), then those without by
/// predicted distance (then shorter flight, then index), keeping only those predicted below `threshold_m`
/// whose footprints overlap every already chosen one by at most `max_iou`; at most `limit`.
///
/// `footprints(candidate)` gives a candidate's obstacle footprints.
pub fn rank(
    screened: &[LfsPrediction],
    threshold_m: f64,
    max_iou: f64,
    limit: usize,
    footprints: impl Fn(CandidateId) -> Vec<Footprint>,
) -> Vec<LfsPrediction> {
    let mut order: Vec<&LfsPrediction> = screened.iter().filter(|s| s.min_distance < threshold_m).collect();
    order.sort_by(|a, b| {
        let rate = |s: &LfsPrediction| s.points_per_minute().map_or(f64::INFINITY, |r| -r);
        rate(a)
            .total_cmp(&rate(b))
            .then(a.min_distance.total_cmp(&b.min_distance))
            .then(a.flight_time_s.total_cmp(&b.flight_time_s))
            .then(a.candidate.cmp(&b.candidate))
    });
    let chosen = distinct(order, |s| s.candidate, max_iou, limit, footprints);
    chosen.into_iter().cloned().collect()
}

/// The items of `order` (candidate `id(item)` each), in order, whose footprints overlap every earlier chosen
/// one's by at most `max_iou`; at most `limit`.
fn distinct<T>(
    order: impl IntoIterator<Item = T>,
    id: impl Fn(&T) -> CandidateId,
    max_iou: f64,
    limit: usize,
    footprints: impl Fn(CandidateId) -> Vec<Footprint>,
) -> Vec<T> {
    let mut chosen: Vec<(T, Vec<Footprint>)> = Vec::new();
    for item in order {
        if chosen.len() >= limit {
            break;
        }
        let f = footprints(id(&item));
        if chosen.iter().all(|(_, g)| union_iou(&f, g) <= max_iou) {
            chosen.push((item, f));
        }
    }
    chosen.into_iter().map(|(item, _)| item).collect()
}

/// A campaign flying unscreened: the candidates of `fresh` in the order drawn, near-duplicates of each other and
/// of every test `seen` skipped (`max_iou`), at most `remaining`.
pub fn in_draw_order(
    fresh: &[CandidateId],
    seen: &Seen,
    candidates: &[Candidate],
    max_iou: f64,
    remaining: usize,
) -> Vec<CandidateId> {
    let obstacles = |c: CandidateId| &candidates[c.index()].obstacles;
    let mut order = fresh.to_vec();
    order.sort();
    let mut chosen = distinct(
        order,
        |c| *c,
        max_iou,
        usize::MAX,
        |c| obstacles(c).iter().map(Obstacle::footprint).collect(),
    );
    chosen.retain(|c| !seen.iter().any(|o| too_similar(o, obstacles(*c), max_iou)));
    chosen.truncate(remaining);
    chosen
}

/// Whether two tests' footprints overlap by more than `max_iou`.
pub(in crate::campaign) fn too_similar(a: &[Obstacle], b: &[Obstacle], max_iou: f64) -> bool {
    let fa: Vec<_> = a.iter().map(Obstacle::footprint).collect();
    let fb: Vec<_> = b.iter().map(Obstacle::footprint).collect();
    union_iou(&fa, &fb) > max_iou
}

/// The obstacles of every test flown or in the air, which a candidate to fly must not copy.
pub type Seen<'a> = [&'a [Obstacle]];

/// The ranking's candidates to fly: near-duplicates of each other and of every test `seen` skipped, at most
/// `remaining`.
pub fn rank_unflown(
    fresh: &[LfsPrediction],
    seen: &Seen,
    candidates: &[Candidate],
    cfg: &CampaignSettings,
    remaining: usize,
) -> Vec<LfsPrediction> {
    rank_unflown_within(fresh, seen, candidates, cfg, remaining, cfg.screening.max_iou)
}

/// As [`rank_unflown`], with candidates allowed to overlap a flown test up to `flown_max_iou` (children of
/// failing flights admitted by [`crate::campaign::plan::diversity_guard`]); among themselves they still obey `max_iou`.
pub fn rank_unflown_within(
    fresh: &[LfsPrediction],
    seen: &Seen,
    candidates: &[Candidate],
    cfg: &CampaignSettings,
    remaining: usize,
    flown_max_iou: f64,
) -> Vec<LfsPrediction> {
    let footprints = |c: CandidateId| {
        candidates[c.index()]
            .obstacles
            .iter()
            .map(Obstacle::footprint)
            .collect()
    };
    let mut ranked = rank(
        fresh,
        cfg.screening.threshold_m,
        cfg.screening.max_iou,
        usize::MAX,
        footprints,
    );
    ranked.retain(|s| {
        !seen
            .iter()
            .any(|o| too_similar(o, &candidates[s.candidate.index()].obstacles, flown_max_iou))
    });
    ranked.truncate(remaining);
    ranked
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(candidate: u64, d: f64, t: f64) -> LfsPrediction {
        LfsPrediction::point(CandidateId(candidate), d, t, "landed".into())
    }

    fn with_points(candidate: u64, d: f64, t: f64, points: f64) -> LfsPrediction {
        LfsPrediction {
            expected_points: Some(points),
            p_fail: Some(points.min(1.0)),
            ..s(candidate, d, t)
        }
    }

    #[test]
    fn ensemble_candidates_go_first_by_points_per_minute() {
        let screened = [
            s(0, 0.2, 40.0),
            // 1 point in 60 s beats 2 points in 180 s; both beat a point prediction without an ensemble.
            with_points(1, 1.4, 60.0, 1.0),
            with_points(2, 0.3, 180.0, 2.0),
            // Above the threshold: never flown, however promising its ensemble.
            with_points(3, 3.5, 30.0, 5.0),
        ];
        let fp = |c: CandidateId| vec![Footprint::from_aerialist(c.0 as f64 * 20.0, 20.0, 4.0, 2.0, 0.0)];
        let r = rank(&screened, 3.0, 0.5, 10, fp);
        assert_eq!(r.iter().map(|s| s.candidate.0).collect::<Vec<_>>(), vec![1, 2, 0]);
        assert_eq!(with_points(1, 1.4, 30.0, 1.0).points_per_minute(), Some(2.0));
    }

    #[test]
    fn severity_order_threshold_limit_and_similarity() {
        let screened = [
            s(0, 2.0, 40.0),
            s(1, 0.5, 50.0),
            s(2, 0.5, 45.0),
            s(3, 5.0, 30.0),
            s(4, 0.1, 60.0),
        ];
        // Candidates 2 and 4 have identical footprints; 4 is more severe, so 2 is skipped.
        let fp = |c: CandidateId| {
            let x = if c.0 == 2 { 40.0 } else { c.0 as f64 * 10.0 };
            vec![Footprint::from_aerialist(x, 20.0, 4.0, 2.0, 0.0)]
        };
        let r = rank(&screened, 3.0, 0.5, 10, fp);
        assert_eq!(r.iter().map(|s| s.candidate.0).collect::<Vec<_>>(), vec![4, 1, 0]);
        let r = rank(&screened, 3.0, 1.0, 2, fp);
        assert_eq!(
            r.iter().map(|s| s.candidate.0).collect::<Vec<_>>(),
            vec![4, 2],
            "ties broken by flight time"
        );
    }
}
