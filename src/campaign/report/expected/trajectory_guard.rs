//! Keeps the written suite free of near-duplicate trajectories, as the 2026 judge sees them: each test's
//! flown flights are averaged the way `evaluate` averages them (origin aligned, 0.5 s bins, soft-DTW
//! barycenter, landing cut) and a test whose average lies within [`GUARD_MARGIN`] x `--similar-below` (DTW
//! on x, y, z) of a better written test's is set aside: the judge would count it as too similar and cut the
//! whole suite.

use std::path::Path;

use crate::campaign::store::journal::FlightRecord;
use crate::campaign::store::journal_check::inside_bytes;
use crate::judge::similarity::{average, path_distance, prepare};
use crate::model::Trajectory;

/// The guard's threshold over the judge's: averages of a campaign's 1-3 flights per test can lie further
/// apart than the judge's 5-flight averages of the same pair, so a pair passes only this far beyond the
/// judge's threshold. Chosen from how the two distances differ (docs/design-constants.md#trajectory-guard-margin).
pub const GUARD_MARGIN: f64 = 1.4;

/// The DTW distance below which the guard sets a test aside when the judge's threshold is `similar_below_m`.
pub fn guard_below(similar_below_m: f64) -> f64 {
    similar_below_m * GUARD_MARGIN
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

/// For each of `averages` (best first), the index among the kept ones of the better kept test it lies
/// within `similar_below_m` of (the closest), or `None` when it is kept. A test without an average cannot
/// be compared and is kept.
pub fn near_duplicates(averages: &[Option<Trajectory>], similar_below_m: f64) -> Vec<Option<usize>> {
    let mut kept: Vec<&Trajectory> = Vec::new();
    let mut out = Vec::with_capacity(averages.len());
    for a in averages {
        let Some(a) = a else {
            out.push(None);
            continue;
        };
        let closest = (kept.iter().enumerate())
            .filter_map(|(k, b)| Some((k, path_distance(a, b)?)))
            .filter(|(_, d)| *d < similar_below_m)
            .min_by(|x, y| x.1.total_cmp(&y.1));
        match closest {
            Some((k, _)) => out.push(Some(k)),
            None => {
                kept.push(a);
                out.push(None);
            }
        }
    }
    out
}

/// The 2026 similarity penalty of tests with these averages: 1 - (tests within `similar_below_m` of an
/// earlier one) / (tests with an average); 1 without any.
pub fn sim_pen(averages: &[Trajectory], similar_below_m: f64) -> f64 {
    if averages.is_empty() {
        return 1.0;
    }
    let similar = (0..averages.len())
        .filter(|&j| (0..j).any(|i| path_distance(&averages[i], &averages[j]).is_some_and(|d| d < similar_below_m)))
        .count();
    1.0 - similar as f64 / averages.len() as f64
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

    #[test]
    fn of_two_identical_trajectories_the_second_is_set_aside() {
        let a = average(&[prepare(&path(0.0))]);
        let dup = near_duplicates(&[a.clone(), a.clone()], 75.0);
        assert_eq!(dup, [None, Some(0)]);
        let averages: Vec<Trajectory> = [a.clone(), a].into_iter().flatten().collect();
        assert_eq!(sim_pen(&averages, 75.0), 0.5);
    }

    #[test]
    fn a_pair_just_beyond_the_judges_threshold_is_set_aside_by_the_margin() {
        let judge = 75.0;
        let (a, b) = (path(0.0), path(6.0));
        let d = path_distance(&a, &b).expect("both have samples");
        assert!(judge < d && d < guard_below(judge), "{d}");
        let averages = [average(&[prepare(&a)]), average(&[prepare(&b)])];
        assert_eq!(near_duplicates(&averages, guard_below(judge)), [None, Some(0)]);
        let flat: Vec<Trajectory> = averages.into_iter().flatten().collect();
        assert_eq!(sim_pen(&flat, judge), 1.0, "the judge would not count them now");
    }

    #[test]
    fn different_trajectories_are_kept() {
        let (a, b) = (path(0.0), path(40.0));
        let d = path_distance(&a, &b).expect("both have samples");
        assert!(d > 75.0, "{d}");
        let averages = [average(&[prepare(&a)]), average(&[prepare(&b)])];
        assert_eq!(near_duplicates(&averages, 75.0), [None, None]);
        let flat: Vec<Trajectory> = averages.into_iter().flatten().collect();
        assert_eq!(sim_pen(&flat, 75.0), 1.0);
        // Set aside against the kept tests only: the third copies the first, not the set-aside second.
        let three = [Some(a.clone()), Some(a.clone()), Some(b), Some(a)];
        assert_eq!(near_duplicates(&three, 75.0), [None, Some(0), None, Some(0)]);
        assert_eq!(
            near_duplicates(&[None, None], 75.0),
            [None, None],
            "nothing to compare: kept"
        );
    }
}
