//! `evaluate`: a suite flown the way the 2026 competition flies it, each test several times, into an
//! evaluation folder with a journal, so a stopped evaluation resumes without flying anything twice.
//!
//! Run `k` of test `i` is journaled as candidate `i * RUN_STRIDE + k` (its trajectory
//! `flights/candidate_<n>.csv`); a folder's tests must not change between resumes.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use super::folder::{load_tests, write_averages};
use super::suite::{Evaluation, FlownTest, evaluate_suite};
use crate::campaign::fly::fleet::fly_all;
use crate::campaign::fly::vehicle::{Job, PoolOutcome, Vehicle};
use crate::campaign::ground::candidate::CandidateId;
use crate::campaign::ground::error::CampaignError;
use crate::campaign::store::folder::FolderLock;
use crate::campaign::store::journal::{FlightRecord, Journal};
use crate::judge::Judge;
use crate::model::{TestCase, Trajectory, load_flight};

/// Candidate numbers per test: runs are `i * RUN_STRIDE + k`, `k` below this.
pub const RUN_STRIDE: u64 = 100;
/// The most runs per test.
pub const MAX_RUNS: usize = 20;
/// The evaluation folder inside the suite's folder.
pub const EVALUATION_DIR: &str = "evaluation";

/// What to evaluate and how.
pub struct EvaluateSetup<'a> {
    /// The suite's folder (`test_N.yaml`, best first).
    pub suite: &'a Path,
    /// Flights per test (1 to [`MAX_RUNS`]).
    pub runs: usize,
    /// Only the first N tests.
    pub top: Option<usize>,
    /// The judge of every flight.
    pub judge: Judge,
    /// The similarity threshold, metres (DTW).
    pub similar_below_m: f64,
    /// Stops the flights: vehicles in the air land; their flights are journaled, not charged.
    pub cancel: &'a AtomicBool,
    /// Told of each journaled flight.
    pub on_flight: &'a (dyn Fn(&FlightRecord) + Sync),
}

/// An evaluation and what its flying did.
pub struct Evaluated {
    /// The 2026 figures over the flights journaled so far.
    pub evaluation: Evaluation,
    /// The evaluation folder.
    pub folder: PathBuf,
    /// Flights still missing (a stopped or failing evaluation; 0 when complete).
    pub missing: usize,
    /// What the fleet did in this run.
    pub outcome: PoolOutcome,
}

/// Flies every test's missing runs on `vehicles`, then evaluates the suite from the journal and writes the
/// averages and `report.json` into `SUITE/evaluation/`. Holds the folder's lock throughout.
pub fn evaluate_by_flying(
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    setup: &EvaluateSetup,
) -> Result<Evaluated, CampaignError> {
    if !(1..=MAX_RUNS).contains(&setup.runs) {
        return Err(CampaignError::Config(format!(
            "--runs {}: expected 1 to {MAX_RUNS} flights per test",
            setup.runs
        )));
    }
    // Absolute, so that the paths report.json names resolve from any directory.
    let suite = std::path::absolute(setup.suite).map_err(|source| crate::model::ModelError::Io {
        path: setup.suite.to_path_buf(),
        action: "cannot resolve",
        source,
    })?;
    let mut tests = load_tests(&suite)?;
    if let Some(n) = setup.top {
        tests.truncate(n.max(1));
    }
    let folder = suite.join(EVALUATION_DIR);
    std::fs::create_dir_all(folder.join("flights")).map_err(|source| crate::model::ModelError::Io {
        path: folder.clone(),
        action: "cannot create",
        source,
    })?;
    let _lock = FolderLock::acquire(&folder)?;
    let journal_path = folder.join("journal.jsonl");
    let (mut journal, _) = Journal::load(&journal_path)?;
    let done = journal.charged();
    check_same_tests(&done, &tests, &journal_path)?;
    let jobs = missing_jobs(&tests, &done, setup.runs);
    let budget = jobs.len();
    let outcome = fly_all(
        vehicles,
        jobs,
        budget,
        &folder,
        &mut journal,
        setup.cancel,
        setup.on_flight,
    );
    if let Some(e) = outcome.errors.first() {
        return Err(CampaignError::Config(e.clone()));
    }
    let done = journal.charged();
    let flown = flown_tests(&tests, &done, &folder, setup.runs)?;
    let missing = tests.len() * setup.runs - flown.iter().map(|t| t.flights.len()).sum::<usize>();
    let (mut evaluation, averages) = evaluate_suite(&flown, setup.judge, setup.similar_below_m)?;
    write_averages(&folder.join("averages"), &mut evaluation, &averages)?;
    super::report::write(&folder, &evaluation, missing)?;
    Ok(Evaluated {
        evaluation,
        folder,
        missing,
        outcome,
    })
}

fn run_of(record: &FlightRecord) -> (usize, usize) {
    (
        (record.candidate.0 / RUN_STRIDE) as usize,
        (record.candidate.0 % RUN_STRIDE) as usize,
    )
}

/// The journal's flights must be of these tests (same obstacles): a changed folder is refused, not mixed.
fn check_same_tests(done: &[FlightRecord], tests: &[(PathBuf, TestCase)], journal: &Path) -> Result<(), CampaignError> {
    for r in done {
        let (i, _) = run_of(r);
        let Some((path, t)) = tests.get(i) else { continue };
        if r.obstacles != t.obstacles {
            return Err(CampaignError::Config(format!(
                "{}: its flights of test {} ({}) had other obstacles: the folder's tests changed since; \
                 evaluate into a fresh folder",
                journal.display(),
                i,
                path.display()
            )));
        }
    }
    Ok(())
}

/// The runs not yet journaled, test by test (best first), run by run.
fn missing_jobs(tests: &[(PathBuf, TestCase)], done: &[FlightRecord], runs: usize) -> Vec<Job> {
    let mut jobs = Vec::new();
    for (i, (_, test)) in tests.iter().enumerate() {
        for k in 0..runs {
            let candidate = CandidateId(i as u64 * RUN_STRIDE + k as u64);
            if done.iter().any(|r| r.candidate == candidate) {
                continue;
            }
            jobs.push(Job::new(candidate, None, test.clone()));
        }
    }
    jobs
}

/// Each test with its journaled flights (the first `runs`), trajectories read from the folder. A flight
/// that ended early (a timeout, a lost link) counts with the trajectory it flew.
fn flown_tests(
    tests: &[(PathBuf, TestCase)],
    done: &[FlightRecord],
    folder: &Path,
    runs: usize,
) -> Result<Vec<FlownTest>, CampaignError> {
    let mut out = Vec::with_capacity(tests.len());
    for (i, (path, test)) in tests.iter().enumerate() {
        let mut mine: Vec<&FlightRecord> = done.iter().filter(|r| run_of(r).0 == i && run_of(r).1 < runs).collect();
        mine.sort_by_key(|r| r.candidate);
        let mut flights: Vec<(PathBuf, Trajectory)> = Vec::with_capacity(mine.len());
        for r in mine {
            let file = folder.join(&r.trajectory);
            match load_flight(&file) {
                Ok(t) if !t.samples.is_empty() => flights.push((file, t)),
                _ => eprintln!(
                    "warning: {}: flight {} of {} left no trajectory ({}): not counted",
                    file.display(),
                    run_of(r).1,
                    path.display(),
                    r.flown.status
                ),
            }
        }
        out.push(FlownTest {
            path: path.clone(),
            test: test.clone(),
            flights,
        });
    }
    Ok(out)
}
