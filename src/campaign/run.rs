//! The campaign's orchestrator: sample candidates, screen them with the LFS, fly the most promising within the
//! budget (in rounds, [`super::conductor`]: learning, or one round without), then report the failing ones best
//! first. Resumable from its folder. [`run_campaign`] is the command line's campaign for the same settings:
//! the screener the mode calls for and the vehicles the settings name.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use tokio::runtime::Handle;

use super::conductor::{load_prior, run_rounds};
use super::fly::backend;
use super::fly::vehicle::Vehicle;
pub use super::ground::error::CampaignError;
pub use super::ground::input::CampaignInput;
pub use super::ground::screener::{Progress, Screener};
use super::ground::stage_times::StageTimes;
use super::learn::calibration::Learnt;
pub use super::report::outputs::Report;
use super::report::outputs::write_outputs;
pub use super::settings::CampaignSettings;
pub use super::settings::resume::FIRST_SETTINGS_FILE;
use super::store::folder::FolderLock;
use super::store::journal::{FlightRecord, Journal};
use super::store::trust::{arena_size_m, check_loaded, check_own_folder, make_own_folder};
use crate::model::{ModelError, TestCase};

/// Runs (or resumes) the campaign `settings` name in `folder`: screened as its mode calls for
/// ([`super::screen::screener_for`]), flown on the vehicles its settings name ([`backend::fleet`], their
/// async tasks on `handle`).
pub fn run_campaign(
    settings: &CampaignSettings,
    folder: &Path,
    progress: &dyn Progress,
    cancel: &AtomicBool,
    handle: &Handle,
) -> Result<Report, CampaignError> {
    check_new(settings)?;
    let vehicles = backend::fleet(&settings.flights(), folder.to_path_buf(), handle)?;
    let screener = super::screen::screener_for(settings);
    run_campaign_with(settings, folder, screener.as_ref(), vehicles, progress, cancel)
}

/// Checks a campaign before anything is drawn or a folder is claimed: every setting, its vehicles' backend
/// (the PX4 build and its mode, the runner's template) and its prior.
pub fn check_new(settings: &CampaignSettings) -> Result<(), CampaignError> {
    settings.check().map_err(CampaignError::Config)?;
    backend::px4_build(&settings.flights())?;
    backend::runner_settings(&settings.flights(), PathBuf::new())?;
    if let Some(p) = &settings.campaign.prior {
        // Refuse a bad prior before anything is sampled or flown.
        load_prior(p)?;
    }
    Ok(())
}

/// Runs (or resumes) a campaign in `folder` with this screener and these vehicles.
pub fn run_campaign_with(
    cfg: &CampaignSettings,
    folder: &Path,
    screener: &dyn Screener,
    mut vehicles: Vec<Box<dyn Vehicle>>,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<Report, CampaignError> {
    cfg.check().map_err(CampaignError::Config)?;
    check_paths_are_text(cfg)?;
    let case = TestCase::load(&cfg.campaign.case)?;
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
fn check_paths_are_text(cfg: &CampaignSettings) -> Result<(), CampaignError> {
    for (what, path) in cfg.paths() {
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
fn prepare_folder(cfg: &CampaignSettings, folder: &Path) -> Result<FolderLock, CampaignError> {
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
        cfg.save(&folder.join(FIRST_SETTINGS_FILE))?;
    }
    cfg.save(&settings)?;
    Ok(lock)
}

/// A campaign ends with the journal's flights written out as tests and reports.
fn finish(
    input: &CampaignInput,
    journal: &Journal,
    drawn: usize,
    stages: StageTimes,
    learning: Option<&Learnt>,
) -> Result<Report, CampaignError> {
    // A campaign that does not screen drew its candidates but screened none of them.
    let screened = if input.cfg.screening.screen { drawn } else { 0 };
    Ok(write_outputs(input, screened, journal, stages, learning)?)
}

#[cfg(test)]
#[path = "run_tests.rs"]
mod tests;
