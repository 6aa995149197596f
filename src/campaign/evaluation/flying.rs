//! `evaluate`: a suite flown the way the 2026 competition flies it, each test several times, into an
//! evaluation folder with a journal, so a stopped evaluation resumes without flying anything twice.
//!
//! Run `k` of test `i` is journaled as candidate `i * RUN_STRIDE + k` (its trajectory
//! `flights/candidate_<n>.csv`); a folder's tests must not change between resumes. The folder is one the
//! evaluation owns ([`crate::campaign::store::trust`]): links in its place are refused, and what the journal says is checked.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use super::folder::write_averages;
use super::listing::{Rules, load_tests};
use super::missing::{Missing, missing};
use super::runs::{MAX_TRIES, RunState, read_runs};
use super::suite::{Evaluation, FlownTest, evaluate_suite};
use crate::campaign::fly::fleet::fly_all;
use crate::campaign::fly::vehicle::{Job, PoolOutcome, Vehicle};
use crate::campaign::ground::error::CampaignError;
use crate::campaign::settings::evaluation::EvaluationSettings;
use crate::campaign::store::folder::FolderLock;
use crate::campaign::store::journal::{FlightRecord, Journal};
use crate::campaign::store::trust::{arena_size_m, check_loaded, check_own_folder, make_own_folder};
use crate::model::{ModelError, TestCase};

pub use super::runs::RUN_STRIDE;

/// The most runs per test.
pub const MAX_RUNS: usize = 20;
/// The evaluation folder inside the suite's folder.
pub const EVALUATION_DIR: &str = "evaluation";
/// Who writes the evaluation folder, as refusals name it.
const WRITER: &str = "evaluate";

/// What to evaluate and how.
pub struct EvaluateSetup<'a> {
    /// The suite's folder (`test_N.yaml`, best first, or any folder of test YAMLs).
    pub suite: &'a Path,
    /// Flights per test (1 to [`MAX_RUNS`]).
    pub runs: usize,
    /// Only the first N tests.
    pub top: Option<usize>,
    /// What the flights fly with (their judge judges them), kept beside the journal.
    pub settings: &'a EvaluationSettings,
    /// The similarity threshold, metres (DTW).
    pub similar_below_m: f64,
    /// Stops the flights: vehicles in the air land; their flights are journaled, not charged.
    pub cancel: &'a AtomicBool,
    /// Told of each journaled flight.
    pub on_flight: &'a (dyn Fn(&FlightRecord) + Sync),
    /// Told of what the user should know (a flight not counted, a torn journal line dropped).
    pub on_warning: &'a (dyn Fn(&str) + Sync),
}

/// An evaluation and what its flying did.
pub struct Evaluated {
    /// The 2026 figures over the flights journaled so far.
    pub evaluation: Evaluation,
    /// The evaluation folder.
    pub folder: PathBuf,
    /// The flights still missing and why (none when complete).
    pub missing: Missing,
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
    let suite = std::path::absolute(setup.suite).map_err(|source| ModelError::Io {
        path: setup.suite.to_path_buf(),
        action: "cannot resolve",
        source,
    })?;
    let tests = load_tests(&suite, setup.top, Rules::Refuse)?;
    let folder = suite.join(EVALUATION_DIR);
    own_folders(&folder)?;
    let _lock = FolderLock::acquire(&folder)?;
    super::kept::keep(&folder, setup.settings, &tests)?;
    let journal_path = folder.join("journal.jsonl");
    let (mut journal, dropped) = Journal::load(&journal_path)?;
    if let Some(dropped) = dropped {
        (setup.on_warning)(&dropped);
    }
    check_loaded(&journal, arena_size_m(&tests[0].1))?;
    check_same_tests(&journal.charged(), &tests, &journal_path)?;
    let first_new = journal.records().len();
    let outcome = fly_missing(vehicles, &tests, &folder, &mut journal, setup)?;
    let numbered = Journal::read_numbered(&journal_path)?;
    let runs = read_runs(&tests, &numbered, &folder, setup.runs);
    let missing = missing(
        &runs,
        &tests,
        &journal.records()[first_new..],
        &outcome,
        &journal_path,
        setup.cancel,
    );
    let flown = flown_tests(&tests, &runs);
    let (mut evaluation, averages) = evaluate_suite(&flown, setup.settings.campaign.judge, setup.similar_below_m)?;
    make_own_folder(&folder.join("averages"), WRITER)?;
    write_averages(&folder.join("averages"), &mut evaluation, &averages)?;
    super::report::write(&folder, &evaluation, &missing)?;
    Ok(Evaluated {
        evaluation,
        folder,
        missing,
        outcome,
    })
}

/// The evaluation folder and the folders it writes into are its own: a link there would carry every write
/// (report, journal, flights, averages) elsewhere.
fn own_folders(folder: &Path) -> Result<(), ModelError> {
    make_own_folder(folder, WRITER)?;
    make_own_folder(&folder.join("flights"), WRITER)?;
    for sub in ["averages", "jobs"] {
        check_own_folder(&folder.join(sub), WRITER)?;
    }
    Ok(())
}

/// Flies the runs without a flight to judge, and again those whose flight left nothing to judge, in rounds
/// until none is left, nothing lands, or every run has had its [`MAX_TRIES`] flights.
fn fly_missing(
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    tests: &[(PathBuf, TestCase)],
    folder: &Path,
    journal: &mut Journal,
    setup: &EvaluateSetup,
) -> Result<PoolOutcome, CampaignError> {
    let mut total = PoolOutcome::default();
    let mut warned: Vec<(u64, u32)> = Vec::new();
    for _ in 0..=MAX_TRIES {
        let records: Vec<(usize, FlightRecord)> = journal.records().iter().map(|r| (0, r.clone())).collect();
        let runs = read_runs(tests, &records, folder, setup.runs);
        warn_unjudged(&runs, tests, &mut warned, setup.on_warning);
        let jobs: Vec<Job> = (runs.iter().filter(|r| r.flies_again()))
            .map(|r| r.job(&tests[r.test].1))
            .collect();
        if jobs.is_empty() || vehicles.is_empty() || setup.cancel.load(Ordering::SeqCst) {
            break;
        }
        let budget = jobs.len();
        let outcome = fly_all(vehicles, jobs, budget, folder, journal, setup.cancel, setup.on_flight);
        if let Some(e) = outcome.errors.first() {
            return Err(CampaignError::Config(e.clone()));
        }
        let landed = outcome.flown;
        add(&mut total, outcome);
        if landed == 0 {
            break;
        }
    }
    Ok(total)
}

/// Tells once of each flight that left nothing to judge, for a run not yet judged.
fn warn_unjudged(
    runs: &[RunState],
    tests: &[(PathBuf, TestCase)],
    warned: &mut Vec<(u64, u32)>,
    warn: &(dyn Fn(&str) + Sync),
) {
    for run in runs.iter().filter(|r| r.judged.is_none()) {
        for u in &run.unjudged {
            let key = (u.record.candidate.0, u.record.attempt);
            if !warned.contains(&key) {
                warned.push(key);
                warn(&format!("warning: {}", run.warning(u, &tests[run.test].0)));
            }
        }
    }
}

fn add(total: &mut PoolOutcome, o: PoolOutcome) {
    total.flown += o.flown;
    total.records.extend(o.records);
    total.dropped.extend(o.dropped);
    total.errors.extend(o.errors);
    total.fleet.vehicles = total.fleet.vehicles.max(o.fleet.vehicles);
    total.fleet.busy_s += o.fleet.busy_s;
    total.fleet.span_s += o.fleet.span_s;
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

/// Each test with the flights its runs are judged on, in run order.
fn flown_tests(tests: &[(PathBuf, TestCase)], runs: &[RunState]) -> Vec<FlownTest> {
    (tests.iter().enumerate())
        .map(|(i, (path, test))| FlownTest {
            path: path.clone(),
            test: test.clone(),
            flights: (runs.iter().filter(|r| r.test == i))
                .filter_map(|r| r.judged.clone())
                .collect(),
        })
        .collect()
}
