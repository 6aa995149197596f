//! A suite flown elsewhere, read from a folder (`score`): its tests ([`super::listing`]) and beside each its
//! flights, `<test>.csv|ulg` and `<test>-K.csv|ulg`; and the averages written out. Every flight is read and
//! checked once, before anything is scored: a damaged or impossible one is refused naming the file.

use std::path::{Path, PathBuf};

use super::listing::{Rules, load_tests};
use super::suite::{Evaluation, FlownTest, evaluate_suite};
use crate::campaign::store::trust::same_folder;
use crate::judge::Judge;
use crate::model::competition::flight_time_rule;
use crate::model::{ModelError, Trajectory, load_flight};

/// The tests of a folder with their flights, in suite order.
#[derive(Debug, Clone)]
pub struct FolderFlights {
    /// The folder.
    pub dir: PathBuf,
    /// Each test with its flights (file and trajectory), in file-name order.
    pub tests: Vec<FlownTest>,
}

impl FolderFlights {
    /// Whether no test has a flight.
    pub fn no_flights(&self) -> bool {
        self.tests.iter().all(|t| t.flights.is_empty())
    }
}

/// Reads the tests of `dir` and every flight beside them (see the module).
pub fn read_folder(dir: &Path) -> Result<FolderFlights, ModelError> {
    let tests = load_tests(dir, None, Rules::Warn)?;
    let paths: Vec<PathBuf> = tests.iter().map(|(p, _)| p.clone()).collect();
    let files = flight_files(dir, &paths).map_err(|source| ModelError::Io {
        path: dir.to_path_buf(),
        action: "cannot list",
        source,
    })?;
    let mut out = Vec::with_capacity(tests.len());
    for ((path, test), files) in tests.into_iter().zip(files) {
        let flights = files
            .into_iter()
            .map(|f| load_scored_flight(&f).map(|t| (f, t)))
            .collect::<Result<Vec<_>, _>>()?;
        out.push(FlownTest { path, test, flights });
    }
    Ok(FolderFlights {
        dir: dir.to_path_buf(),
        tests: out,
    })
}

/// A flight to score: read as [`load_flight`] reads it (damage refused), and long enough to be a flight
/// ([`flight_time_rule`]).
pub fn load_scored_flight(path: &Path) -> Result<Trajectory, ModelError> {
    let flight = load_flight(path)?;
    match flight_time_rule(flight.duration_s()) {
        Some(why) => Err(ModelError::Syntax {
            path: path.to_path_buf(),
            line: None,
            column: None,
            message: format!("{why}: refused rather than scored"),
        }),
        None => Ok(flight),
    }
}

/// Each test's flight files in `dir`: `<stem>.csv|ulg` and `<stem>-K.csv|ulg`, in name order. A file two
/// tests' names match (`a-1.csv` beside `a.yaml` and `a-1.yaml`) is the longer name's.
pub fn flight_files(dir: &Path, tests: &[PathBuf]) -> std::io::Result<Vec<Vec<PathBuf>>> {
    let stems: Vec<String> = (tests.iter())
        .map(|p| {
            p.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .collect();
    let mut out = vec![Vec::new(); tests.len()];
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for p in entries {
        let flight = p
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| e == "csv" || e == "ulg");
        let Some(s) = p.file_stem().and_then(|s| s.to_str()).filter(|_| flight) else {
            continue;
        };
        let owner = (0..stems.len())
            .filter(|&i| s == stems[i] || s.strip_prefix(stems[i].as_str()).is_some_and(|r| r.starts_with('-')))
            .max_by_key(|&i| stems[i].len());
        if let Some(i) = owner {
            out[i].push(p);
        }
    }
    Ok(out)
}

/// Scores a folder of tests with their recorded flights the 2026 way. A test without flights is listed
/// but not evaluated (no runs, score 0, outside `sim_pen`'s count). `averages`, if given, is the folder the
/// average trajectories are written to (`test_N.csv`): never the folder scored, whose flights those names are.
pub fn evaluate_folder(
    folder: &FolderFlights,
    judge: Judge,
    similar_below_m: f64,
    averages: Option<&Path>,
) -> Result<Evaluation, ModelError> {
    if let Some(out) = averages {
        refuse_scored_folder(out, &folder.dir)?;
    }
    let (mut evaluation, trajectories) = evaluate_suite(&folder.tests, judge, similar_below_m)?;
    if let Some(out) = averages {
        std::fs::create_dir_all(out).map_err(|source| ModelError::Io {
            path: out.to_path_buf(),
            action: "cannot create",
            source,
        })?;
        write_averages(out, &mut evaluation, &trajectories)?;
    }
    Ok(evaluation)
}

/// The averages' names are the flights' (`test_N.csv`): written into the scored folder they would replace them.
fn refuse_scored_folder(out: &Path, scored: &Path) -> Result<(), ModelError> {
    if same_folder(out, scored) {
        return Err(ModelError::Io {
            path: out.to_path_buf(),
            action: "cannot write the averages into",
            source: std::io::Error::other(format!(
                "it is the folder scored, and an average test_N.csv would replace the flight of that name there; \
                 give another folder (such as {})",
                scored.join("averages").display()
            )),
        });
    }
    Ok(())
}

/// Writes each test's average as `OUT/<test stem>.csv` (the folder exists) and names it in the evaluation.
pub fn write_averages(
    out: &Path,
    evaluation: &mut Evaluation,
    trajectories: &[Option<Trajectory>],
) -> Result<(), ModelError> {
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
