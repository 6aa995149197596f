//! Keeps the written suite free of near-duplicate trajectories, as the 2026 judge sees them: each test's
//! flown flights are averaged the way `evaluate` averages them (origin aligned, 0.5 s bins, soft-DTW
//! barycenter, landing cut) and compared (DTW on x, y, z) with the better tests already written. The
//! campaign's averages rest on 1-3 flights, the judge's on 5 fresh ones, so a campaign distance only gives
//! the chance that the judge finds the pair too similar ([`flag_probability`]). A test is written when that
//! chance is at most [`MAX_FLAG_PROBABILITY`] and it raises the suite's expected 2026 score, its own expected
//! score against the share of the suite's `sim_pen` it may cost ([`choose`]).

use std::path::Path;

use crate::campaign::report::expected::expected_points::normal_cdf;
use crate::campaign::store::journal::FlightRecord;
use crate::campaign::store::trust::inside_bytes;
use crate::judge::similarity::{average, path_distance, prepare};
use crate::model::Trajectory;

/// Median of the judge's over the campaign's DTW distance of the same pair of tests. With
/// [`RATIO_LOG_SD`], a log-normal fitted to the quantiles measured on the mock
/// (docs/design-constants.md#trajectory-guard).
pub const RATIO_MEDIAN: f64 = 0.95;

/// Standard deviation of the ratio's logarithm.
pub const RATIO_LOG_SD: f64 = 0.2;

/// A test the judge more likely than not finds too similar to a better written test is never written: the
/// suite is kept free of near-duplicates even where a copy of a strong test would pay.
pub const MAX_FLAG_PROBABILITY: f64 = 0.5;

/// The chance that the judge's 5-flight averages of a pair lie closer than `similar_below_m` when the
/// campaign's averages lie `campaign_m` apart (DTW, metres).
pub fn flag_probability(campaign_m: f64, similar_below_m: f64) -> f64 {
    if campaign_m.is_nan() || campaign_m <= 0.0 {
        return 1.0;
    }
    normal_cdf(((similar_below_m / campaign_m).ln() - RATIO_MEDIAN.ln()) / RATIO_LOG_SD)
}

/// The campaign distance below which [`flag_probability`] exceeds [`MAX_FLAG_PROBABILITY`] (metres): the
/// closest a written test can lie to a better one.
pub fn guard_below(similar_below_m: f64) -> f64 {
    // With the cap at 0.5 this is where the ratio's median brings the campaign distance to the threshold.
    similar_below_m / RATIO_MEDIAN
}

/// The average of the flights `records` whose trajectories (relative to `folder`) can be read; `None` when
/// none can.
pub fn flown_average(folder: &Path, records: &[&FlightRecord]) -> Option<Trajectory> {
    let flights: Vec<Trajectory> = records
        .iter()
        .filter(|r| r.flown.min_distance.is_some())
        .filter_map(|r| {
            let text = String::from_utf8(inside_bytes(folder, &r.trajectory)?).ok()?;
            Trajectory::parse_csv(&text, &r.trajectory).ok()
        })
        .filter(|t| !t.samples.is_empty())
        .map(|t| prepare(&t))
        .collect();
    if flights.is_empty() {
        return None;
    }
    average(&flights)
}

/// The guard's verdict on one test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Guarded {
    /// Written.
    Kept {
        /// The chance the judge finds it too similar to a better written test.
        flag_probability: f64,
    },
    /// Set aside: it flies like a better kept test.
    Copies {
        /// That test's index among the kept ones (0 = the first kept).
        kept: usize,
        /// The DTW distance between the two flown averages, metres.
        dtw_m: f64,
    },
}

/// The guard over `tests` (best first: each test's flown average and expected score): walks them in order and
/// keeps a test when its [`flag_probability`] against the kept ones is at most [`MAX_FLAG_PROBABILITY`] and
/// the suite's expected score, (sum of scores) x (1 - expected similar tests / tests), does not fall. A test
/// without an average cannot be compared and is kept.
pub fn choose(tests: &[(Option<Trajectory>, f64)], similar_below_m: f64) -> Vec<Guarded> {
    // Each kept average with its index among all kept tests (those without an average count too).
    let mut kept: Vec<(usize, &Trajectory)> = Vec::new();
    let (mut total, mut similar, mut n) = (0.0, 0.0, 0.0);
    let mut out = Vec::with_capacity(tests.len());
    for (average, score) in tests {
        let distances: Vec<(usize, f64)> = match average {
            Some(a) => (kept.iter())
                .filter_map(|(k, b)| Some((*k, path_distance(a, b)?)))
                .collect(),
            None => Vec::new(),
        };
        let apart: f64 = (distances.iter())
            .map(|(_, d)| 1.0 - flag_probability(*d, similar_below_m))
            .product();
        let q = 1.0 - apart;
        let before = if n > 0.0 { total * (1.0 - similar / n) } else { 0.0 };
        let after = (total + score) * (1.0 - (similar + q) / (n + 1.0));
        let closest = distances.iter().copied().min_by(|x, y| x.1.total_cmp(&y.1));
        match closest {
            Some((k, d)) if q > MAX_FLAG_PROBABILITY || after < before => {
                out.push(Guarded::Copies { kept: k, dtw_m: d })
            }
            _ => {
                if let Some(a) = average {
                    kept.push((n as usize, a));
                }
                (total, similar, n) = (total + score, similar + q, n + 1.0);
                out.push(Guarded::Kept { flag_probability: q });
            }
        }
    }
    out
}

/// The expected 2026 similarity penalty of the tests `choose` kept: 1 - expected similar tests / tests.
pub fn expected_sim_pen(verdicts: &[Guarded]) -> f64 {
    let q: Vec<f64> = (verdicts.iter())
        .filter_map(|v| match v {
            Guarded::Kept { flag_probability } => Some(*flag_probability),
            Guarded::Copies { .. } => None,
        })
        .collect();
    if q.is_empty() {
        return 1.0;
    }
    1.0 - q.iter().sum::<f64>() / q.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Sample;

    /// A straight flight north, then east by `east` metres over its second half.
    fn path(east: f64) -> Trajectory {
        let samples = (0..60)
            .map(|i| {
                let t = f64::from(i) * 0.5;
                let y = if i < 30 { 0.0 } else { east * f64::from(i - 30) / 30.0 };
                Sample {
                    t_s: t,
                    x: t,
                    y,
                    z: 5.0,
                    r: None,
                }
            })
            .collect();
        Trajectory::new(samples)
    }

    fn averaged(east: f64) -> Option<Trajectory> {
        average(&[prepare(&path(east))])
    }

    #[test]
    fn the_flag_probability_falls_with_the_campaign_distance() {
        let p = |d: f64| flag_probability(d, 75.0);
        assert_eq!((p(0.0), p(f64::NAN)), (1.0, 1.0));
        // guard_below is where the chance crosses the cap (its median form holds for a cap of 0.5).
        assert!((p(guard_below(75.0)) - MAX_FLAG_PROBABILITY).abs() < 1e-6);
        assert!(p(50.0) > 0.95 && p(150.0) < 0.01, "{} {}", p(50.0), p(150.0));
        // The log-normal's 10 % quantile: the old fixed margin of 1.4 let pairs through at about this chance.
        let p10 = RATIO_MEDIAN * (-1.281_551_565_545 * RATIO_LOG_SD).exp();
        assert!((p(75.0 / p10) - 0.1).abs() < 1e-6);
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-9 && (normal_cdf(1.96) - 0.975).abs() < 1e-4);
        let mut last = 1.0;
        for d in (10..400).map(f64::from) {
            assert!(p(d) <= last, "monotone at {d}");
            last = p(d);
        }
    }

    #[test]
    fn an_identical_trajectory_is_set_aside_and_a_different_one_kept() {
        let (a, b) = (averaged(0.0), averaged(40.0));
        let d = path_distance(a.as_ref().unwrap(), b.as_ref().unwrap()).expect("both have samples");
        assert!(flag_probability(d, 75.0) < 0.01, "{d}");
        let v = choose(&[(a.clone(), 1.0), (a.clone(), 1.0), (b, 1.0), (a, 5.0)], 75.0);
        assert_eq!(v[0], Guarded::Kept { flag_probability: 0.0 });
        assert!(
            matches!(v[1], Guarded::Copies { kept: 0, dtw_m } if dtw_m < 1e-9),
            "{v:?}"
        );
        assert!(
            matches!(v[2], Guarded::Kept { flag_probability } if flag_probability < 0.01),
            "{v:?}"
        );
        // Never written while more likely similar than not, however well it scores.
        assert!(matches!(v[3], Guarded::Copies { kept: 0, .. }), "{v:?}");
        assert!(expected_sim_pen(&v) > 0.99);
    }

    #[test]
    fn a_test_near_the_threshold_is_written_when_its_score_outweighs_the_risk() {
        let (a, b) = (averaged(0.0), averaged(8.0));
        let d = path_distance(a.as_ref().unwrap(), b.as_ref().unwrap()).expect("both have samples");
        let q = flag_probability(d, 75.0);
        assert!(0.02 < q && q < MAX_FLAG_PROBABILITY, "{d} m: {q}");
        let strong = choose(&[(a.clone(), 1.0), (b.clone(), 1.0)], 75.0);
        assert_eq!(strong[1], Guarded::Kept { flag_probability: q });
        assert!((expected_sim_pen(&strong) - (1.0 - q / 2.0)).abs() < 1e-12);
        // A weak one would cost the suite more through sim_pen than it adds.
        let weak = choose(&[(a, 1.0), (b, 0.01)], 75.0);
        assert!(matches!(weak[1], Guarded::Copies { kept: 0, .. }), "{weak:?}");
    }

    #[test]
    fn a_copy_names_its_test_among_all_kept_ones() {
        let a = averaged(0.0);
        let v = choose(&[(None, 1.0), (a.clone(), 1.0), (a, 1.0)], 75.0);
        assert_eq!(
            v[2],
            Guarded::Copies { kept: 1, dtw_m: 0.0 },
            "the kept test without an average counts"
        );
        assert_eq!(choose(&[(None, 1.0), (None, 1.0)], 75.0).len(), 2);
    }
}
