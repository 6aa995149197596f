//! Ranking screened candidates: most severe predicted flights first, near-duplicates skipped.

use serde::{Deserialize, Serialize};

use crate::geometry::{Footprint, union_iou};

/// What the low-fidelity simulator predicted for one candidate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Screened {
    /// The candidate's generator index.
    pub candidate: u64,
    /// Predicted minimum distance (competition definition), metres.
    pub min_distance: f64,
    /// Predicted flight time, seconds.
    pub flight_time_s: f64,
    /// How the simulated flight ended.
    pub status: String,
}

/// Orders candidates by predicted distance (then shorter flight, then index), keeping only those predicted
/// below `threshold_m` whose footprints overlap every already chosen one by at most `max_iou`; at most `limit`.
///
/// `footprints(candidate)` gives a candidate's obstacle footprints.
pub fn rank(
    screened: &[Screened],
    threshold_m: f64,
    max_iou: f64,
    limit: usize,
    footprints: impl Fn(u64) -> Vec<Footprint>,
) -> Vec<Screened> {
    let mut order: Vec<&Screened> = screened.iter().filter(|s| s.min_distance < threshold_m).collect();
    order.sort_by(|a, b| {
        a.min_distance
            .total_cmp(&b.min_distance)
            .then(a.flight_time_s.total_cmp(&b.flight_time_s))
            .then(a.candidate.cmp(&b.candidate))
    });
    let mut chosen: Vec<(Screened, Vec<Footprint>)> = Vec::new();
    for s in order {
        if chosen.len() >= limit {
            break;
        }
        let f = footprints(s.candidate);
        if chosen.iter().all(|(_, g)| union_iou(&f, g) <= max_iou) {
            chosen.push((s.clone(), f));
        }
    }
    chosen.into_iter().map(|(s, _)| s).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(candidate: u64, d: f64, t: f64) -> Screened {
        Screened {
            candidate,
            min_distance: d,
            flight_time_s: t,
            status: "landed".into(),
        }
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
        let fp = |c: u64| {
            let x = if c == 2 { 40.0 } else { c as f64 * 10.0 };
            vec![Footprint::from_aerialist(x, 20.0, 4.0, 2.0, 0.0)]
        };
        let r = rank(&screened, 3.0, 0.5, 10, fp);
        assert_eq!(r.iter().map(|s| s.candidate).collect::<Vec<_>>(), vec![4, 1, 0]);
        let r = rank(&screened, 3.0, 1.0, 2, fp);
        assert_eq!(
            r.iter().map(|s| s.candidate).collect::<Vec<_>>(),
            vec![4, 2],
            "ties broken by flight time"
        );
    }
}
