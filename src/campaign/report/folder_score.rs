//! The competition's metrics for a folder of tests with flights (competition.md section 4).

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::geometry::union_iou;
use crate::judge::{Judge, diversity, judge_flight, points, test_score};
use crate::model::{ModelError, Obstacle, TestCase, load_flight};

/// Tests whose footprints overlap this much (IoU) count as duplicates of an earlier one.
pub const DUPLICATE_IOU: f64 = 0.999;

/// One flight of a test.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunScore {
    /// The flight file (trajectory CSV or ULog).
    pub file: PathBuf,
    /// The competition's minimum distance, metres.
    pub min_distance: f64,
    /// The un-binned minimum distance, metres.
    pub min_distance_raw: f64,
    /// Flight duration, seconds.
    pub flight_time_s: f64,
    /// Points of this run (5, 2, 1 or 0).
    pub points: u32,
}

/// One test and its flights.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TestScore {
    /// The test YAML.
    pub test: PathBuf,
    /// Number of obstacles.
    pub obstacles: usize,
    /// Its flights, in file-name order.
    pub runs: Vec<RunScore>,
    /// The test score (0 without flights or as a duplicate).
    pub score: f64,
    /// Whether any run came closer than 1.5 m.
    pub failed: bool,
    /// Index of the earlier test it duplicates, if any (its score is then not counted).
    pub duplicate_of: Option<usize>,
}

/// A suite's metrics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SuiteScore {
    /// The judge edition of every distance and point here.
    pub judge: Judge,
    /// Its definition in one line.
    pub judge_definition: &'static str,
    /// Per test, in test order.
    pub tests: Vec<TestScore>,
    /// Sum of the test scores, duplicates excluded.
    pub failure_score: f64,
    /// Tests with at least one run below 1.5 m (duplicates excluded).
    pub failing: usize,
    /// Tests with at least one flight.
    pub evaluated: usize,
    /// 1 - mean pairwise IoU of the failing tests' obstacle footprints (`None` below two failing tests).
    pub diversity: Option<f64>,
}

/// Scores one test from its runs' flights.
pub fn score_test(
    test: &TestCase,
    test_path: &Path,
    flights: &[PathBuf],
    judge: Judge,
) -> Result<TestScore, ModelError> {
    let mut runs = Vec::new();
    for f in flights {
        let trajectory = load_flight(f)?;
        let Some(verdict) = judge_flight(&trajectory, &test.obstacles, judge) else {
            return Err(ModelError::field(
                test_path,
                "simulation.obstacles",
                "no obstacles to measure against",
            ));
        };
        runs.push(RunScore {
            file: f.clone(),
            min_distance: verdict.min_distance,
            min_distance_raw: verdict.min_distance_raw,
            flight_time_s: trajectory.duration_s(),
            points: points(verdict.min_distance),
        });
    }
    let distances: Vec<f64> = runs.iter().map(|r| r.min_distance).collect();
    let times: Vec<f64> = runs.iter().map(|r| r.flight_time_s).collect();
    Ok(TestScore {
        test: test_path.to_path_buf(),
        obstacles: test.obstacles.len(),
        score: test_score(&distances, &times, test.obstacles.len()),
        failed: distances.iter().any(|d| *d < crate::model::competition::FAIL_BELOW_M),
        runs,
        duplicate_of: None,
    })
}

/// The flights of `test_N.yaml` in its folder: `test_N.csv`, `test_N.ulg`, and runs named `test_N-*.csv|ulg`.
pub fn flights_of(test_path: &Path) -> Vec<PathBuf> {
    let (Some(dir), Some(stem)) = (test_path.parent(), test_path.file_stem().and_then(|s| s.to_str())) else {
        return Vec::new();
    };
    let Ok(entries) = std::fs::read_dir(if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    }) else {
        return Vec::new();
    };
    let mut out: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            let ext_ok = p
                .extension()
                .and_then(|e| e.to_str())
                .is_some_and(|e| e == "csv" || e == "ulg");
            let s = p.file_stem().and_then(|s| s.to_str()).unwrap_or("");
            ext_ok && (s == stem || s.strip_prefix(stem).is_some_and(|rest| rest.starts_with('-')))
        })
        .collect();
    out.sort();
    out
}

/// The tests of a folder, `test_0.yaml`, `test_1.yaml`, ... in numeric order (other YAML files are ignored).
pub fn tests_in(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut tests: Vec<(u64, PathBuf)> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let n = p
                .file_name()?
                .to_str()?
                .strip_prefix("test_")?
                .strip_suffix(".yaml")?
                .parse()
                .ok()?;
            Some((n, p))
        })
        .collect();
    tests.sort();
    Ok(tests.into_iter().map(|(_, p)| p).collect())
}

/// Scores a suite: marks duplicates and sums the failure score.
pub fn score_suite(mut tests: Vec<TestScore>, obstacles: &[Vec<Obstacle>], judge: Judge) -> SuiteScore {
    let prints: Vec<Vec<_>> = obstacles
        .iter()
        .map(|o| o.iter().map(Obstacle::footprint).collect())
        .collect();
    for i in 0..tests.len() {
        tests[i].duplicate_of = (0..i).find(|&j| union_iou(&prints[i], &prints[j]) >= DUPLICATE_IOU);
        if tests[i].duplicate_of.is_some() {
            tests[i].score = 0.0;
        }
    }
    let counted = || tests.iter().filter(|t| t.duplicate_of.is_none());
    SuiteScore {
        judge,
        judge_definition: judge.description(),
        failure_score: counted().map(|t| t.score).sum::<f64>() + 0.0,
        failing: counted().filter(|t| t.failed).count(),
        evaluated: tests.iter().filter(|t| !t.runs.is_empty()).count(),
        diversity: failing_diversity(&tests, obstacles),
        tests,
    }
}

/// The diversity of the tests that failed, as the competition defines it; rounding noise of identical layouts
/// (1 - 1.0000000000000004) reads 0.
fn failing_diversity(tests: &[TestScore], obstacles: &[Vec<Obstacle>]) -> Option<f64> {
    let failing: Vec<Vec<Obstacle>> = (tests.iter().zip(obstacles))
        .filter(|(t, _)| t.failed)
        .map(|(_, o)| o.clone())
        .collect();
    diversity(&failing).map(|d| if d.abs() < 1e-9 { 0.0 } else { d })
}

/// Scores every `test_N.yaml` of a folder with its flights.
pub fn score_folder(dir: &Path, judge: Judge) -> Result<SuiteScore, ModelError> {
    let io = |source| ModelError::Io {
        path: dir.to_path_buf(),
        action: "cannot list",
        source,
    };
    let paths = tests_in(dir).map_err(io)?;
    let mut scores = Vec::new();
    let mut obstacles = Vec::new();
    for p in &paths {
        let test = TestCase::load(p)?;
        scores.push(score_test(&test, p, &flights_of(p), judge)?);
        obstacles.push(test.obstacles);
    }
    Ok(score_suite(scores, &obstacles, judge))
}
