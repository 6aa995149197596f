//! The 2026 figures of a suite from its tests' flights: per test the runs' points, mean points, score and
//! average trajectory; per pair of tests the DTW distance of their averages; the similar tests, `sim_pen`
//! and the final score; the 2025 figures beside them.

use std::path::PathBuf;

use serde::Serialize;

use crate::judge::similarity::{average, path_distance, prepare};
use crate::judge::{AboveTop, Judge, diversity, judge_flight, points, test_score, test_score_sd};
use crate::model::competition::FAIL_BELOW_M;
use crate::model::{ModelError, TestCase, Trajectory};

/// A test and the flights it made.
#[derive(Debug, Clone)]
pub struct FlownTest {
    /// The test YAML.
    pub path: PathBuf,
    /// The test.
    pub test: TestCase,
    /// Each flight: its file and its trajectory (as recorded; aligned and binned here).
    pub flights: Vec<(PathBuf, Trajectory)>,
}

/// One flight of a test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Run {
    /// The flight's trajectory file.
    pub trajectory: PathBuf,
    /// The judged minimum distance, metres.
    pub min_distance: f64,
    /// Its points (5, 2, 1 or 0).
    pub points: u32,
    /// Flight time, seconds.
    pub flight_time_s: f64,
    /// Set when the vehicle was above the box's top at its closest approach: the judge's distance is
    /// horizontal there (the 2026 judge scores a crossing over a box 0 m).
    pub above_top: Option<AboveTop>,
}

/// One test's 2026 figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TestEvaluation {
    /// The test YAML.
    pub test: PathBuf,
    /// Number of obstacles.
    pub obstacles: usize,
    /// Its flights, in order.
    pub runs: Vec<Run>,
    /// Mean points over the runs (0 without runs).
    pub mean_points: f64,
    /// Mean flight time over the runs, seconds.
    pub mean_flight_time_s: f64,
    /// mean points x 10 / (obstacles² x mean flight minutes); 0 without runs.
    pub score: f64,
    /// The standard error of `score` from the runs' own scatter: score per point x the points' sample
    /// standard deviation / √runs (`None` below 2 runs).
    pub score_sd: Option<f64>,
    /// The CSV of its average trajectory, once written.
    pub average_trajectory: Option<PathBuf>,
    /// Index of the earlier test whose average lies within the threshold, if any.
    pub similar_to: Option<usize>,
}

/// The DTW distance between two tests' average trajectories.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Pair {
    /// The first test's YAML.
    pub a: PathBuf,
    /// The second test's YAML.
    pub b: PathBuf,
    /// DTW distance of the averages on x, y, z, metres summed over the alignment.
    pub dtw: f64,
    /// Whether it is below the threshold.
    pub similar: bool,
}

/// The 2025 figures of the same flights, for comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Figures2025 {
    /// Tests with any run below 1.5 m.
    pub failing: usize,
    /// Sum of the failing tests' scores.
    pub failure_score: f64,
    /// 1 - mean pairwise footprint IoU of the failing tests (`None` below two).
    pub diversity: Option<f64>,
}

/// A suite's 2026 evaluation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    /// The judge edition of every distance and point.
    pub judge: Judge,
    /// Its definition in one line.
    pub judge_definition: &'static str,
    /// The similarity threshold, metres (DTW).
    pub similar_below_m: f64,
    /// Per test, in suite order (best first).
    pub tests: Vec<TestEvaluation>,
    /// Every pair of tests with an average.
    pub pairs: Vec<Pair>,
    /// Tests with at least one flight.
    pub evaluated: usize,
    /// Tests whose average lies within the threshold of an earlier test's.
    pub similar_tests: usize,
    /// 1 - similar_tests / evaluated (1 with nothing evaluated).
    pub sim_pen: f64,
    /// Sum of the test scores.
    pub total_score: f64,
    /// Its standard error from the runs' own scatter, the tests taken as independent (`None` when an
    /// evaluated test has fewer than 2 runs). It leaves out whatever moves a whole evaluation: on PX4 two
    /// evaluations of one suite differed by 1.0-1.7 times this (docs/evaluate.md).
    pub total_score_sd: Option<f64>,
    /// total_score x sim_pen.
    pub final_score: f64,
    /// The same flights the 2025 way.
    pub figures_2025: Figures2025,
}

/// Evaluates a suite. Returns the evaluation and each test's average trajectory (`None` without flights),
/// for the caller to write. Errors: a test without obstacles to judge against.
pub fn evaluate_suite(
    tests: &[FlownTest],
    judge: Judge,
    similar_below_m: f64,
) -> Result<(Evaluation, Vec<Option<Trajectory>>), ModelError> {
    let mut evaluated = Vec::with_capacity(tests.len());
    let mut averages = Vec::with_capacity(tests.len());
    for t in tests {
        evaluated.push(evaluate_test(t, judge)?);
        let prepared: Vec<Trajectory> = t.flights.iter().map(|(_, f)| prepare(f)).collect();
        averages.push(average(&prepared));
    }
    let dists = pair_distances(&averages);
    let mut similar_tests = 0;
    for (i, t) in evaluated.iter_mut().enumerate() {
        t.similar_to = dists
            .iter()
            .filter(|&&(a, b, d)| b == i && a < i && d < similar_below_m)
            .map(|&(a, _, _)| a)
            .min();
        similar_tests += usize::from(t.similar_to.is_some());
    }
    let pairs = dists
        .into_iter()
        .map(|(i, j, dtw)| Pair {
            a: tests[i].path.clone(),
            b: tests[j].path.clone(),
            dtw,
            similar: dtw < similar_below_m,
        })
        .collect();
    let n_evaluated = evaluated.iter().filter(|t| !t.runs.is_empty()).count();
    let sim_pen = if n_evaluated == 0 {
        1.0
    } else {
        1.0 - similar_tests as f64 / n_evaluated as f64
    };
    // + 0.0 on every sum: an empty f64 sum is -0.0, printed "-0.000".
    let total_score = evaluated.iter().map(|t| t.score).sum::<f64>() + 0.0;
    let total_score_sd = total_sd(&evaluated);
    let figures_2025 = figures_2025(tests, &evaluated);
    let evaluation = Evaluation {
        judge,
        judge_definition: judge.description(),
        similar_below_m,
        evaluated: n_evaluated,
        similar_tests,
        sim_pen,
        total_score,
        total_score_sd,
        final_score: total_score * sim_pen + 0.0,
        figures_2025,
        pairs,
        tests: evaluated,
    };
    Ok((evaluation, averages))
}

/// The total's standard error: the root sum of squares of the evaluated tests' (`None` when one has none, or
/// none is evaluated).
fn total_sd(tests: &[TestEvaluation]) -> Option<f64> {
    let mut evaluated = tests.iter().filter(|t| !t.runs.is_empty()).peekable();
    evaluated.peek()?;
    let sum = evaluated.map(|t| t.score_sd.map(|sd| sd * sd)).sum::<Option<f64>>()?;
    Some((sum + 0.0).sqrt())
}

fn evaluate_test(t: &FlownTest, judge: Judge) -> Result<TestEvaluation, ModelError> {
    let mut runs = Vec::with_capacity(t.flights.len());
    for (file, flight) in &t.flights {
        let Some(verdict) = judge_flight(flight, &t.test.obstacles, judge) else {
            return Err(ModelError::field(
                &t.path,
                "simulation.obstacles",
                "no obstacles to measure against (or an empty flight)",
            ));
        };
        runs.push(Run {
            trajectory: file.clone(),
            min_distance: verdict.min_distance,
            points: points(verdict.min_distance),
            flight_time_s: flight.duration_s(),
            above_top: verdict.above_top,
        });
    }
    let n = runs.len().max(1) as f64;
    let mean_points = runs.iter().map(|r| f64::from(r.points)).sum::<f64>() / n + 0.0;
    let mean_flight_time_s = runs.iter().map(|r| r.flight_time_s).sum::<f64>() / n + 0.0;
    let distances: Vec<f64> = runs.iter().map(|r| r.min_distance).collect();
    let times: Vec<f64> = runs.iter().map(|r| r.flight_time_s).collect();
    let k = t.test.obstacles.len();
    let score = test_score(&distances, &times, k);
    let score_sd = test_score_sd(&distances, &times, k);
    Ok(TestEvaluation {
        test: t.path.clone(),
        obstacles: t.test.obstacles.len(),
        runs,
        mean_points,
        mean_flight_time_s,
        score,
        score_sd,
        average_trajectory: None,
        similar_to: None,
    })
}

/// DTW of every pair of averages `(i, j, distance)` with `i < j`, the pairs split over the machine's cores.
fn pair_distances(averages: &[Option<Trajectory>]) -> Vec<(usize, usize, f64)> {
    let index: Vec<(usize, usize)> = (0..averages.len())
        .flat_map(|i| (i + 1..averages.len()).map(move |j| (i, j)))
        .filter(|&(i, j)| averages[i].is_some() && averages[j].is_some())
        .collect();
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get()).clamp(1, 16);
    let chunk = index.len().div_ceil(workers).max(1);
    let distance = |&(i, j): &(usize, usize)| match (&averages[i], &averages[j]) {
        (Some(a), Some(b)) => (i, j, path_distance(a, b).unwrap_or(f64::INFINITY)),
        _ => (i, j, f64::INFINITY),
    };
    std::thread::scope(|s| {
        let handles: Vec<_> = index
            .chunks(chunk)
            .map(|part| s.spawn(move || part.iter().map(distance).collect::<Vec<_>>()))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    })
}

/// The 2025 way: a test fails when any run is below 1.5 m; footprint diversity of the failing tests.
fn figures_2025(tests: &[FlownTest], evaluated: &[TestEvaluation]) -> Figures2025 {
    let failing: Vec<usize> = (0..tests.len())
        .filter(|&i| evaluated[i].runs.iter().any(|r| r.min_distance < FAIL_BELOW_M))
        .collect();
    let obstacles: Vec<Vec<_>> = failing.iter().map(|&i| tests[i].test.obstacles.clone()).collect();
    Figures2025 {
        failing: failing.len(),
        // + 0.0: an empty f64 sum is -0.0, printed "-0.000".
        failure_score: failing.iter().map(|&i| evaluated[i].score).sum::<f64>() + 0.0,
        diversity: diversity(&obstacles),
    }
}

#[cfg(test)]
#[path = "suite_tests.rs"]
mod tests;
