//! The campaign's orchestrator: sample candidates, screen them with the LFS, fly the most promising within the
//! budget (in rounds, [`super::plan::rounds`]: learning, or one round without), then report the failing ones best
//! first. Resumable from its folder.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

pub use super::config::{CampaignConfig, CampaignError, CampaignInput, DEFAULT_MOCK_LATENCY_MS, check_counts};
use super::fly::vehicle::Vehicle;
use super::learn::calibration::Learnt;
use super::plan::rounds::run_rounds;
pub use super::report::outputs::Report;
use super::report::outputs::{StageTimes, write_outputs};
pub use super::screen::screener::{Progress, Screener};
use super::store::folder::FolderLock;
use super::store::journal::{FlightRecord, Journal};
use super::store::trust::{arena_size_m, check_loaded, check_own_folder, make_own_folder};
use crate::io::write_json;
use crate::model::{ModelError, TestCase};

/// Runs (or resumes) a campaign in `folder`.
pub fn run_campaign(
    cfg: &CampaignConfig,
    folder: &Path,
    screener: &dyn Screener,
    mut vehicles: Vec<Box<dyn Vehicle>>,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<Report, CampaignError> {
    super::setup::check_settings(cfg)?;
    check_paths_are_text(cfg)?;
    let case = TestCase::load(&cfg.case)?;
    let _writer = prepare_folder(cfg, folder)?;
    // Read once, and healed before anything appends: a record must never follow a torn line.
    let (mut journal, dropped) = Journal::load(&folder.join("journal.jsonl"))?;
    if let Some(dropped) = dropped {
        progress.warn(&dropped);
    }
    check_loaded(&journal, arena_size_m(&case))?;
    if let Some(orphans) = unjournaled_trajectories(folder, journal.records()) {
        progress.warn(&orphans);
    }
    let input = CampaignInput {
        cfg,
        folder,
        case: &case,
        screener,
        progress,
        cancel,
    };
    let mut stages = StageTimes::default();
    // A resume replays the plan: the journaled flights are taken where it has them, the rest are flown.
    match run_rounds(&input, &mut vehicles, &mut journal, &mut stages) {
        Ok((learnt, drawn)) => finish(&input, &journal, drawn, stages, learnt.as_ref()),
        Err(e) => report_if_stopped(e, &input, &journal, stages),
    }
}

/// A campaign stopped (Ctrl-C, SIGTERM, SIGHUP) in a stage that cannot end early with a result, screening
/// say, still reports the flights journaled so far: the stop is the user's, not an error.
fn report_if_stopped(
    e: CampaignError,
    input: &CampaignInput,
    journal: &Journal,
    stages: StageTimes,
) -> Result<Report, CampaignError> {
    if !input.cancel.load(std::sync::atomic::Ordering::SeqCst) {
        return Err(e);
    }
    input
        .progress
        .warn(&format!("stopped ({e}); reporting the flights journaled so far"));
    finish(input, journal, 0, stages, None)
}

/// Says so when `flights/` holds trajectories the journal has no record of (a journal deleted or emptied, or a
/// flight in the air when the campaign was killed): those flights are flown again, and the user should know.
fn unjournaled_trajectories(folder: &Path, records: &[FlightRecord]) -> Option<String> {
    let journal = folder.join("journal.jsonl");
    let known: HashSet<&PathBuf> = records.iter().map(|r| &r.trajectory).collect();
    let Ok(entries) = std::fs::read_dir(folder.join("flights")) else {
        return None;
    };
    let mut orphans: Vec<String> = entries
        .filter_map(Result::ok)
        .map(|e| PathBuf::from("flights").join(e.file_name()))
        .filter(|p| p.extension().is_some_and(|x| x == "csv") && !known.contains(p))
        .map(|p| p.display().to_string())
        .collect();
    if orphans.is_empty() {
        return None;
    }
    orphans.sort();
    let shown = orphans.iter().take(5).cloned().collect::<Vec<_>>().join(", ");
    Some(format!(
        "{}: {} trajectory file(s) in flights/ have no journal record ({shown}{}): flights not journaled (the \
         campaign was killed mid-flight, or the journal was emptied or removed); they are not part of the \
         campaign's results; a candidate among them that the campaign flies again gets a new file in its place, \
         the others are left as they are",
        journal.display(),
        orphans.len(),
        if orphans.len() > 5 { ", ..." } else { "" }
    ))
}

/// `campaign.json` keeps its paths as JSON text, so a path that is not UTF-8 could never be resumed.
fn check_paths_are_text(cfg: &CampaignConfig) -> Result<(), CampaignError> {
    let paths = [("the case", Some(&cfg.case)), ("--prior", cfg.prior.as_ref())];
    for (what, path) in paths {
        if let Some(p) = path.filter(|p| p.to_str().is_none()) {
            return Err(CampaignError::Config(format!(
                "{what} {}: the path is not UTF-8, and campaign.json stores paths as text for --resume; \
                 rename or move the file to a UTF-8 path",
                p.display()
            )));
        }
    }
    Ok(())
}

/// Creates the folder, takes its one-writer lock (held while the campaign runs) and saves the settings as
/// `campaign.json` (what `--resume` continues).
fn prepare_folder(cfg: &CampaignConfig, folder: &Path) -> Result<FolderLock, CampaignError> {
    std::fs::create_dir_all(folder).map_err(|source| ModelError::Io {
        path: folder.to_path_buf(),
        action: "cannot create",
        source,
    })?;
    let lock = FolderLock::acquire(folder)?;
    // The folders the campaign writes into must be its own: a link there would carry every write elsewhere.
    make_own_folder(&folder.join("flights"), "the campaign")?;
    check_own_folder(&folder.join("jobs"), "the campaign")?;
    let settings = folder.join("campaign.json");
    // What the campaign began with, kept apart: a resume shows what was changed in campaign.json since.
    if std::fs::symlink_metadata(&settings).is_err() {
        write_json(&folder.join(FIRST_SETTINGS_FILE), cfg, true)?;
    }
    write_json(&settings, cfg, true)?;
    Ok(lock)
}

/// `campaign.json` as the campaign's first run wrote it, never rewritten.
pub const FIRST_SETTINGS_FILE: &str = "campaign.first.json";

/// A campaign ends with the journal's flights written out as tests and reports.
fn finish(
    input: &CampaignInput,
    journal: &Journal,
    drawn: usize,
    stages: StageTimes,
    learning: Option<&Learnt>,
) -> Result<Report, CampaignError> {
    // A campaign that does not screen drew its candidates but screened none of them.
    let screened = if input.cfg.screen { drawn } else { 0 };
    Ok(write_outputs(input, screened, journal, stages, learning)?)
}

#[cfg(test)]
#[path = "run_tests.rs"]
mod tests;
