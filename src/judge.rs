//! How the competition judges a flight (`docs/formats.md`, judging and scoring): minimum distance to the obstacles,
//! points per run and the test score. Two definitions of the distance exist ([`Judge`], see [`edition`]).

mod closest;
pub mod cp_verdict;
pub mod edition;
pub mod similarity;
pub mod wilson;

use serde::Serialize;

pub use edition::Judge;
pub use wilson::{Z90, wilson_interval};

use crate::geometry::{Footprint, P2};
use crate::model::competition::{RUN_POINTS, TEST_SCORE_SCALE};
use crate::model::{AERIALIST_BIN_S, Obstacle, Sample, Trajectory};

/// Distance of a flight to one obstacle, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ObstacleDistance {
    /// Index of the obstacle in the test.
    pub index: usize,
    /// The judged value: 0.5 s bins, the edition's definition.
    pub distance: f64,
    /// The same rule on the path without binning.
    pub distance_raw: f64,
}

/// Where the un-binned path came closest to an obstacle (the judged frame, `x` North, `y` East, `z` up).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClosestApproach {
    /// Seconds from the first sample.
    pub t_s: f64,
    /// North, metres.
    pub x: f64,
    /// East, metres.
    pub y: f64,
    /// Height, metres.
    pub z: f64,
    /// The obstacle's index.
    pub obstacle: usize,
    /// The distance there, metres (the edition's definition).
    pub distance: f64,
}

/// The verdict on one flight.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FlightDistance {
    /// The edition whose definition gave these numbers.
    pub judge: Judge,
    /// That definition in one line.
    pub judge_definition: &'static str,
    /// The competition's minimum distance, metres.
    pub min_distance: f64,
    /// The continuous minimum distance on the un-binned path, metres.
    pub min_distance_raw: f64,
    /// Per obstacle, in test order.
    pub per_obstacle: Vec<ObstacleDistance>,
    /// Closest approach on the un-binned path.
    pub closest: ClosestApproach,
    /// Whether the un-binned bare path entered a box (a physical collision, whatever the edition).
    pub collision: bool,
    /// Set when the vehicle was higher than the box's top at its closest approach (having crossed over
    /// it, or passed beside it above the top). The distance is then horizontal, a closeness the vehicle
    /// never had: in the 2026 edition always, in the 2025 one beside the box (over it, that edition
    /// counts the height gap).
    pub above_top: Option<AboveTop>,
}

/// The vehicle above a box's top where it came closest to the box.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AboveTop {
    /// The obstacle's index (from 0, in test order).
    pub obstacle: usize,
    /// The vehicle's height there minus the box's, metres (positive).
    pub height_m: f64,
}

/// Judges a recorded log against obstacles, as Aerialist does; `None` without samples or obstacles.
///
/// The trajectory is first origin-aligned (its first sample becomes the origin, as Aerialist's
/// `ALLIGN_ORIGIN`, right for logs that start at home), then judged by [`judge_in_frame`].
pub fn judge_flight(trajectory: &Trajectory, obstacles: &[Obstacle], judge: Judge) -> Option<FlightDistance> {
    judge_in_frame(&trajectory.origin_aligned(), obstacles, judge)
}

/// Judges a trajectory that is already in the obstacles' frame (no alignment); `None` without samples or
/// obstacles. The competition's value uses 0.5 s bin averages, the raw value every sample.
pub fn judge_in_frame(trajectory: &Trajectory, obstacles: &[Obstacle], judge: Judge) -> Option<FlightDistance> {
    if trajectory.samples.is_empty() || obstacles.is_empty() {
        return None;
    }
    let raw = trajectory;
    let binned = raw.binned(AERIALIST_BIN_S);
    let mut collision = false;
    let per_obstacle: Vec<ObstacleDistance> = obstacles
        .iter()
        .enumerate()
        .map(|(index, o)| {
            // The raw path's bare distance once: the edition's value and the collision both come from it.
            let (f, bare) = bare_distance(o, &raw.samples);
            let over = || lowest_over(&f, &raw.samples);
            // A collision is the bare path inside a box, whatever the edition's buffer says.
            collision |= Judge::E2025.from_bare(bare, o.size.h, over) == 0.0;
            ObstacleDistance {
                index,
                distance: judged_distance(judge, o, &binned.samples),
                distance_raw: judge.from_bare(bare, o.size.h, over),
            }
        })
        .collect();
    let min = |f: fn(&ObstacleDistance) -> f64| per_obstacle.iter().map(f).fold(f64::INFINITY, f64::min);
    let closest = closest::closest_approach(judge, obstacles, &raw.samples);
    let above_top = (obstacles.get(closest.obstacle))
        .map(|o| closest.z - o.size.h)
        .filter(|h| *h > 0.0)
        .map(|height_m| AboveTop {
            obstacle: closest.obstacle,
            height_m,
        });
    Some(FlightDistance {
        judge,
        judge_definition: judge.description(),
        min_distance: min(|d| d.distance),
        min_distance_raw: min(|d| d.distance_raw),
        per_obstacle,
        closest,
        collision,
        above_top,
    })
}

/// The distance from `obstacle` to `path` by `judge`'s definition.
pub fn judged_distance(judge: Judge, obstacle: &Obstacle, path: &[Sample]) -> f64 {
    let (f, d) = bare_distance(obstacle, path);
    judge.from_bare(d, obstacle.size.h, || lowest_over(&f, path))
}

/// The obstacle's footprint and its 2-D distance to `path` as a polyline (infinite without a sample).
fn bare_distance(obstacle: &Obstacle, path: &[Sample]) -> (Footprint, f64) {
    let f = obstacle.footprint();
    let pts: Vec<P2> = path.iter().map(|s| P2::new(s.x, s.y)).collect();
    let d = f.distance_to_polyline(&pts).unwrap_or(f64::INFINITY);
    (f, d)
}

/// Aerialist's `Obstacle.distance` (the 2025 edition): 2-D distance from the footprint to the path as a
/// polyline; when that is 0 and the path over the footprint is higher than the box everywhere, the height gap.
pub fn obstacle_distance(obstacle: &Obstacle, path: &[Sample]) -> f64 {
    judged_distance(Judge::E2025, obstacle, path)
}

/// Lowest height of the path where it lies over the footprint (heights interpolated along segments).
fn lowest_over(f: &Footprint, path: &[Sample]) -> Option<f64> {
    let mut low: Option<f64> = None;
    let mut see = |z: f64| low = Some(low.map_or(z, |l| l.min(z)));
    if let [s] = path
        && f.contains(P2::new(s.x, s.y))
    {
        see(s.z);
    }
    for w in path.windows(2) {
        let (a, b) = (P2::new(w[0].x, w[0].y), P2::new(w[1].x, w[1].y));
        if let Some((t0, t1)) = f.clip_segment(a, b) {
            // Height is linear along a segment, so its minimum over [t0, t1] is at an end.
            let z = |t: f64| w[0].z + (w[1].z - w[0].z) * t;
            see(z(t0).min(z(t1)));
        }
    }
    low
}

/// The competition's points for one run ([`RUN_POINTS`]: 5 below 0.25 m, 2 below 1 m, 1 below 1.5 m, else 0).
pub fn points(min_distance: f64) -> u32 {
    RUN_POINTS
        .iter()
        .find(|(below_m, _)| min_distance < *below_m)
        .map_or(0, |(_, points)| *points)
}

/// Test score: mean points x 10 / (obstacles^2 x mean flight time in minutes); 0 when undefined.
pub fn test_score(run_distances: &[f64], run_flight_times_s: &[f64], obstacle_count: usize) -> f64 {
    if run_distances.is_empty() || run_flight_times_s.is_empty() || obstacle_count == 0 {
        return 0.0;
    }
    let mean_points = run_distances.iter().map(|d| f64::from(points(*d))).sum::<f64>() / run_distances.len() as f64;
    let minutes = run_flight_times_s.iter().sum::<f64>() / run_flight_times_s.len() as f64 / 60.0;
    if minutes <= 0.0 {
        return 0.0;
    }
    mean_points * TEST_SCORE_SCALE / ((obstacle_count * obstacle_count) as f64 * minutes)
}

/// The standard error of [`test_score`] from the runs' own scatter: score per point x the points' sample
/// standard deviation / √runs; `None` below 2 runs.
pub fn test_score_sd(run_distances: &[f64], run_flight_times_s: &[f64], obstacle_count: usize) -> Option<f64> {
    let n = run_distances.len();
    if n < 2 {
        return None;
    }
    let minutes = run_flight_times_s.iter().sum::<f64>() / run_flight_times_s.len().max(1) as f64 / 60.0;
    let per_point = if obstacle_count == 0 || minutes <= 0.0 {
        0.0
    } else {
        TEST_SCORE_SCALE / ((obstacle_count * obstacle_count) as f64 * minutes)
    };
    let p: Vec<f64> = run_distances.iter().map(|d| f64::from(points(*d))).collect();
    let mean = p.iter().sum::<f64>() / n as f64;
    let var = p.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    Some(per_point * (var / n as f64).sqrt())
}

/// How many of `flags` are set, and the lowest height above a box's top among them (`None` when none is).
pub fn above_top_count(flags: impl IntoIterator<Item = Option<AboveTop>>) -> Option<(usize, f64)> {
    let heights: Vec<f64> = flags.into_iter().flatten().map(|a| a.height_m).collect();
    Some((heights.len(), heights.into_iter().reduce(f64::min)?))
}

/// The competition's diversity of a suite: 1 - mean pairwise IoU of the tests' obstacle footprints;
/// `None` for fewer than two tests.
pub fn diversity(tests: &[Vec<Obstacle>]) -> Option<f64> {
    if tests.len() < 2 {
        return None;
    }
    let prints: Vec<Vec<Footprint>> = tests.iter().map(|t| footprints(t)).collect();
    let (mut sum, mut pairs) = (0.0, 0usize);
    for i in 0..prints.len() {
        for j in i + 1..prints.len() {
            sum += crate::geometry::union_iou(&prints[i], &prints[j]);
            pairs += 1;
        }
    }
    Some(1.0 - sum / pairs as f64)
}

/// A test's obstacle footprints, what the competition's similarity compares.
fn footprints(test: &[Obstacle]) -> Vec<Footprint> {
    test.iter().map(Obstacle::footprint).collect()
}

/// How many of `tests` (in order, best first) overlap no earlier *kept* test by more than `max_iou`: the suite
/// counted once per place, a close variant of a kept test not counted again. Not a competition metric: it
/// says how much of a suite's failure count is close variants, which its diversity averages away.
pub fn distinct_tests(tests: &[Vec<Obstacle>], max_iou: f64) -> usize {
    let mut kept: Vec<Vec<Footprint>> = Vec::new();
    for t in tests {
        let p = footprints(t);
        if kept.iter().all(|k| crate::geometry::union_iou(&p, k) <= max_iou) {
            kept.push(p);
        }
    }
    kept.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(points: &[(f64, f64, f64, f64)]) -> Trajectory {
        Trajectory::new(
            points
                .iter()
                .map(|&(t_s, x, y, z)| Sample { t_s, x, y, z, r: None })
                .collect(),
        )
    }

    #[test]
    fn straight_pass_beside_a_box() {
        let o = Obstacle::new(4.0, 2.0, 20.0, 10.0, 3.0, 0.0);
        let t = path(&[(0.0, 0.0, 0.0, 0.0), (5.0, 20.0, 0.0, 10.0)]);
        let j = judge_flight(&t, &[o], Judge::E2025).unwrap();
        assert!((j.min_distance - 2.0).abs() < 1e-12);
        assert!((j.min_distance_raw - 2.0).abs() < 1e-12);
        assert!(!j.collision);
        assert!(
            (7.999..=12.0).contains(&j.closest.x) && j.closest.y.abs() < 1e-9,
            "{:?}",
            j.closest
        );
        assert!((j.closest.distance - 2.0).abs() < 1e-9);
    }

    #[test]
    fn passing_over_a_low_box_counts_the_height_gap() {
        let o = Obstacle::new(2.0, 2.0, 5.0, 10.0, 0.0, 0.0);
        let t = path(&[(0.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 8.0), (2.0, 20.0, 0.0, 8.0)]);
        let j = judge_flight(&t, &[o], Judge::E2025).unwrap();
        assert!((j.min_distance_raw - 3.0).abs() < 1e-12);
        let crash = path(&[(0.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 4.0), (2.0, 20.0, 0.0, 4.0)]);
        assert!(judge_flight(&crash, &[o], Judge::E2025).unwrap().collision);
    }

    #[test]
    fn a_closest_approach_above_a_box_top_is_named_with_its_height_in_either_edition() {
        let low = Obstacle::new(2.0, 2.0, 5.0, 10.0, 0.0, 0.0);
        let beside = Obstacle::new(2.0, 2.0, 5.0, 10.0, 1.5, 0.0);
        let far = Obstacle::new(2.0, 2.0, 20.0, 10.0, 30.0, 0.0);
        let tall = Obstacle::new(2.0, 2.0, 20.0, 10.0, 0.0, 0.0);
        let over = path(&[(0.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 8.0), (2.0, 20.0, 0.0, 8.0)]);
        for judge in Judge::ALL {
            // Straight over the low box, or 0.5 m beside the other one: 3 m above either's top.
            for o in [low, beside] {
                let j = judge_flight(&over, &[far, o], judge).unwrap();
                let a = j.above_top.expect("above the top");
                assert_eq!(a.obstacle, 1, "{judge}");
                assert!((a.height_m - 3.0).abs() < 1e-9, "{judge}: {}", a.height_m);
            }
            // A box taller than the flight: nothing above its top.
            let j = judge_flight(&over, &[tall], judge).unwrap();
            assert!(j.above_top.is_none() && j.collision, "{judge}");
        }
    }

    #[test]
    fn the_2026_edition_measures_from_the_buffered_path_horizontally() {
        let o = Obstacle::new(4.0, 2.0, 20.0, 10.0, 3.0, 0.0);
        let beside = path(&[(0.0, 0.0, 0.0, 0.0), (5.0, 20.0, 0.0, 10.0)]);
        let j = judge_flight(&beside, &[o], Judge::E2026).unwrap();
        assert!((j.min_distance - 1.875).abs() < 1e-12 && (j.min_distance_raw - 1.875).abs() < 1e-12);
        assert!((j.closest.distance - 1.875).abs() < 1e-9);
        assert_eq!(
            (j.judge, j.judge_definition),
            (Judge::E2026, Judge::E2026.description())
        );
        // Over a low box: 2025 counts the 3 m height gap, 2026 only the horizontal 0 (but no collision).
        let low = Obstacle::new(2.0, 2.0, 5.0, 10.0, 0.0, 0.0);
        let over = path(&[(0.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 8.0), (2.0, 20.0, 0.0, 8.0)]);
        assert!((judge_flight(&over, &[low], Judge::E2025).unwrap().min_distance_raw - 3.0).abs() < 1e-12);
        let j = judge_flight(&over, &[low], Judge::E2026).unwrap();
        assert_eq!(j.min_distance_raw, 0.0);
        assert!(!j.collision, "flying over a box is no collision");
        let json = serde_json::to_value(&j).unwrap();
        assert_eq!(json["judge"], "2026");
        assert!(json["judge_definition"].as_str().unwrap().contains("0.125"));
    }

    #[test]
    fn judging_in_frame_does_not_align_the_origin() {
        let o = Obstacle::new(2.0, 2.0, 5.0, 10.0, 0.0, 0.0);
        // Starts 2 m East of the test's home: in the frame it passes 1 m beside the box; aligned to its
        // first sample it would run through it.
        let t = path(&[(0.0, 0.0, 2.0, 0.0), (5.0, 20.0, 2.0, 0.0)]);
        let framed = judge_in_frame(&t, &[o], Judge::E2025).unwrap();
        let aligned = judge_flight(&t, &[o], Judge::E2025).unwrap();
        assert!(
            (framed.min_distance_raw - 1.0).abs() < 1e-12,
            "{}",
            framed.min_distance_raw
        );
        assert!(!framed.collision && aligned.collision);
    }

    #[test]
    fn binning_changes_the_competition_value_only() {
        // A swerve towards the box lasting one sample is averaged away by the 0.5 s bins.
        let o = Obstacle::new(2.0, 2.0, 20.0, 5.0, 3.0, 0.0);
        let mut pts: Vec<(f64, f64, f64, f64)> =
            (0..=20).map(|i| (i as f64 * 0.1, i as f64 * 0.5, 0.0, 10.0)).collect();
        pts[10].2 = 1.5; // at x = 5, 0.5 m from the box's near side (y = 2)
        let j = judge_flight(&path(&pts), &[o], Judge::E2025).unwrap();
        assert!((j.min_distance_raw - 0.5).abs() < 1e-12);
        assert!(j.min_distance > 1.5, "binned {}", j.min_distance);
    }

    #[test]
    fn diversity_of_identical_and_disjoint_suites() {
        let a = vec![Obstacle::new(2.0, 2.0, 20.0, 0.0, 20.0, 0.0)];
        let b = vec![Obstacle::new(2.0, 2.0, 20.0, 10.0, 20.0, 0.0)];
        assert_eq!(diversity(&[a.clone(), a.clone()]), Some(0.0));
        assert_eq!(diversity(&[a.clone(), b]), Some(1.0));
        assert_eq!(diversity(&[a]), None);
    }

    #[test]
    fn distinct_tests_count_each_place_once() {
        let at = |x: f64| vec![Obstacle::new(2.0, 2.0, 20.0, x, 20.0, 0.0)];
        // Shifted 0.5 m: IoU 1.5 / 2.5 = 0.6; shifted 1 m: 1 / 3 = 0.33; 10 m: 0.
        assert_eq!(distinct_tests(&[at(0.0), at(0.5), at(10.0)], 0.5), 2);
        assert_eq!(distinct_tests(&[at(0.0), at(0.5), at(10.0)], 0.7), 3);
        assert_eq!(distinct_tests(&[at(0.0), at(1.0), at(10.0)], 0.5), 3);
        // Greedy in order: 0.5 is a variant of 0.0 and of 1.0, which is kept (IoU 0.33 to 0.0).
        assert_eq!(distinct_tests(&[at(0.0), at(1.0), at(0.5)], 0.5), 2);
        assert_eq!(distinct_tests(&[], 0.5), 0);
    }

    #[test]
    fn points_and_score() {
        assert_eq!([0.1, 0.5, 1.2, 2.0].map(points), [5, 2, 1, 0]);
        // 2 obstacles, two runs of 60 s with 5 and 1 points: mean 3 x 10 / (4 x 1) = 7.5.
        assert!((test_score(&[0.1, 1.2], &[60.0, 60.0], 2) - 7.5).abs() < 1e-12);
        assert_eq!(test_score(&[], &[], 2), 0.0);
    }
}
