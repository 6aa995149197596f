//! A suite flown elsewhere, read from a folder: `test_N.yaml` with its flights `test_N.csv|ulg` and
//! `test_N-K.csv|ulg` (`score`), and the averages written beside the report.

use std::path::{Path, PathBuf};

use crate::campaign::report::folder_score::{flights_of, tests_in};
use crate::judge::Judge;
use crate::model::{ModelError, TestCase, Trajectory, load_flight};

use super::suite::{Evaluation, FlownTest, evaluate_suite};

fn io_error(path: &Path, action: &'static str) -> impl FnOnce(std::io::Error) -> ModelError {
    let path = path.to_path_buf();
    move |source| ModelError::Io { path, action, source }
}

/// Loads the tests of a folder, refusing tests of different missions (the competition evaluates one
/// mission at a time).
pub fn load_tests(dir: &Path) -> Result<Vec<(PathBuf, TestCase)>, ModelError> {
    let paths = tests_in(dir).map_err(io_error(dir, "cannot list"))?;
    if paths.is_empty() {
        return Err(ModelError::field(dir, "test_N.yaml", "the folder holds no test"));
    }
    let mut tests: Vec<(PathBuf, TestCase)> = Vec::with_capacity(paths.len());
    for p in paths {
        let t = TestCase::load(&p)?;
        if let Some((first, f)) = tests.first()
            && (f.mission.items != t.mission.items || f.mission.home != t.mission.home)
        {
            return Err(ModelError::field(
                &p,
                "mission_file",
                format!(
                    "flies another mission than {} ({} vs {}); evaluate one mission per folder",
                    first.display(),
                    t.mission_file,
                    f.mission_file
                ),
            ));
        }
        tests.push((p, t));
    }
    Ok(tests)
}

/// Scores a folder of tests with their recorded flights the 2026 way. A test without flights is listed
/// but not evaluated (no runs, score 0, outside `sim_pen`'s count). `averages`, if given, is the folder the
/// average trajectories are written to (`test_N.csv`).
pub fn evaluate_folder(
    dir: &Path,
    judge: Judge,
    similar_below_m: f64,
    averages: Option<&Path>,
) -> Result<Evaluation, ModelError> {
    let mut flown = Vec::new();
    for (path, test) in load_tests(dir)? {
        let files = flights_of(&path);
        let flights = files
            .into_iter()
            .map(|f| load_flight(&f).map(|t| (f, t)))
            .collect::<Result<Vec<_>, _>>()?;
        flown.push(FlownTest { path, test, flights });
    }
    let (mut evaluation, trajectories) = evaluate_suite(&flown, judge, similar_below_m)?;
    if let Some(out) = averages {
        write_averages(out, &mut evaluation, &trajectories)?;
    }
    Ok(evaluation)
}

/// Writes each test's average as `OUT/<test stem>.csv` and names it in the evaluation.
pub fn write_averages(
    out: &Path,
    evaluation: &mut Evaluation,
    trajectories: &[Option<Trajectory>],
) -> Result<(), ModelError> {
    std::fs::create_dir_all(out).map_err(io_error(out, "cannot create"))?;
    for (t, avg) in evaluation.tests.iter_mut().zip(trajectories) {
        let (Some(avg), Some(stem)) = (avg, t.test.file_stem()) else {
            continue;
        };
        let file = out.join(stem).with_extension("csv");
        crate::io::write_atomic(&file, avg.to_csv().as_bytes())?;
        t.average_trajectory = Some(file);
    }
    Ok(())
}
