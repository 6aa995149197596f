//! The competition's metrics for a folder of tests with flights (competition.md section 4).

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::FlownTest;
use super::folder::{FolderFlights, read_folder};
use crate::geometry::union_iou;
use crate::judge::{Judge, diversity, judge_flight, points, test_score};
use crate::model::{ModelError, Obstacle};

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

/// Scores one test from its runs' flights (each file with its trajectory).
pub fn score_test(test: &FlownTest, judge: Judge) -> Result<TestScore, ModelError> {
    let mut runs = Vec::new();
    for (file, trajectory) in &test.flights {
        let Some(verdict) = judge_flight(trajectory, &test.test.obstacles, judge) else {
            return Err(ModelError::field(
                &test.path,
                "simulation.obstacles",
                "no obstacles to measure against",
            ));
        };
        runs.push(RunScore {
            file: file.clone(),
            min_distance: verdict.min_distance,
            min_distance_raw: verdict.min_distance_raw,
            flight_time_s: trajectory.duration_s(),
            points: points(verdict.min_distance),
        });
    }
    let distances: Vec<f64> = runs.iter().map(|r| r.min_distance).collect();
    let times: Vec<f64> = runs.iter().map(|r| r.flight_time_s).collect();
    let k = test.test.obstacles.len();
    Ok(TestScore {
        test: test.path.clone(),
        obstacles: k,
        score: test_score(&distances, &times, k),
        failed: distances.iter().any(|d| *d < crate::model::competition::FAIL_BELOW_M),
        runs,
        duplicate_of: None,
    })
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

/// The diversity of the tests that failed, as the competition defines it, over the tests counted (a duplicate
/// is not: it would pull the diversity down for a test the failure score leaves out); rounding noise of
/// identical layouts (1 - 1.0000000000000004) reads 0.
fn failing_diversity(tests: &[TestScore], obstacles: &[Vec<Obstacle>]) -> Option<f64> {
    let failing: Vec<Vec<Obstacle>> = (tests.iter().zip(obstacles))
        .filter(|(t, _)| t.failed && t.duplicate_of.is_none())
        .map(|(_, o)| o.clone())
        .collect();
    diversity(&failing).map(|d| if d.abs() < 1e-9 { 0.0 } else { d })
}

/// Scores the tests of a folder read with their flights.
pub fn score_flights(folder: &FolderFlights, judge: Judge) -> Result<SuiteScore, ModelError> {
    let scores = folder
        .tests
        .iter()
        .map(|t| score_test(t, judge))
        .collect::<Result<Vec<_>, _>>()?;
    let obstacles: Vec<Vec<Obstacle>> = folder.tests.iter().map(|t| t.test.obstacles.clone()).collect();
    Ok(score_suite(scores, &obstacles, judge))
}

/// Scores every test of a folder with its flights ([`read_folder`]).
pub fn score_folder(dir: &Path, judge: Judge) -> Result<SuiteScore, ModelError> {
    score_flights(&read_folder(dir)?, judge)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn failed(file: &str) -> TestScore {
        TestScore {
            test: file.into(),
            obstacles: 1,
            runs: Vec::new(),
            score: 1.0,
            failed: true,
            duplicate_of: None,
        }
    }

    #[test]
    fn a_duplicate_test_does_not_count_in_the_diversity() {
        let a = Obstacle::new(2.0, 2.0, 20.0, 4.0, 25.0, 0.0);
        let b = Obstacle::new(2.0, 2.0, 20.0, 4.0, 26.0, 0.0);
        let tests = vec![failed("test_0.yaml"), failed("test_1.yaml"), failed("test_2.yaml")];
        let suite = score_suite(tests, &[vec![a], vec![b], vec![a]], Judge::E2026);
        assert_eq!(suite.tests[2].duplicate_of, Some(0));
        assert_eq!(suite.failing, 2);
        let two = diversity(&[vec![a], vec![b]]).unwrap();
        assert_eq!(suite.diversity, Some(two), "the 2 counted tests' diversity");
    }
}
