//! The flight stage: a ranking flown on the vehicles within the budget, each flight journaled.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use super::candidate::{Candidate, Screened};
use super::config::CampaignError;
use super::journal::{FlightRecord, Journal};
use super::pool::{Job, Vehicle, fly_all};
use super::screener::Progress;
use crate::model::TestCase;

/// What the flight stage reads.
pub struct FlightStage<'a> {
    /// The case study.
    pub case: &'a TestCase,
    /// Every candidate drawn so far, by index.
    pub candidates: &'a [Candidate],
    /// The campaign folder (journal, trajectories).
    pub folder: &'a Path,
    /// Progress output.
    pub progress: &'a dyn Progress,
    /// Stops the flights (vehicles in the air land).
    pub cancel: &'a AtomicBool,
}

/// Flies `ranked` in order on `vehicles` within `remaining` flights, journaling each; returns the flights made,
/// as the journal reads them back, in its order.
/// A journal error stops the campaign; so does a fleet with no vehicle left (every one dropped, in this call or
/// an earlier round's), keeping the flights journaled so far for `--resume`: a campaign that lost every vehicle
/// must not end as a clean run that found no failing test.
pub fn fly_ranked(
    ctx: &FlightStage,
    ranked: Vec<Screened>,
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    remaining: usize,
) -> Result<Vec<FlightRecord>, CampaignError> {
    let jobs: Vec<Job> = ranked
        .into_iter()
        .map(|s| Job {
            test: ctx
                .case
                .with_obstacles(ctx.candidates[s.candidate as usize].obstacles.clone()),
            screened: s,
        })
        .collect();
    if jobs.is_empty() {
        return Ok(Vec::new());
    }
    let no_vehicle_left = |why: String| {
        CampaignError::NoVehicle(format!(
            "{why}; the flights so far are journaled: resume with  prgenuav generate --resume {}",
            ctx.folder.display()
        ))
    };
    if vehicles.is_empty() {
        return Err(no_vehicle_left("every vehicle was dropped in an earlier round".into()));
    }
    let progress = ctx.progress;
    progress.stage("fly", jobs.len());
    let count = AtomicUsize::new(0);
    let on_flight = |r: &FlightRecord| announce(progress, count.fetch_add(1, Ordering::Relaxed) + 1, r);
    let journal_path = ctx.folder.join("journal.jsonl");
    let outcome = fly_all(
        vehicles,
        jobs,
        remaining,
        ctx.folder,
        Journal::open(&journal_path)?,
        ctx.cancel,
        &on_flight,
    );
    for d in &outcome.dropped {
        progress.note(&format!("dropped {d}"));
    }
    if let Some(e) = outcome.errors.first() {
        return Err(CampaignError::Config(format!("journal: {e}")));
    }
    if vehicles.is_empty() {
        return Err(no_vehicle_left(outcome.dropped.join("; ")));
    }
    Ok(outcome.records)
}

/// On resume, flies the flights the user interrupted before anything else (they were the most promising
/// candidates when they took off), within what the budget has left; returns how many were flown.
pub fn fly_interrupted(
    ctx: &FlightStage,
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    budget_left: usize,
) -> Result<usize, CampaignError> {
    let journal_path = ctx.folder.join("journal.jsonl");
    let pending = Journal::interrupted(&journal_path)?;
    if pending.is_empty() || budget_left == 0 || vehicles.is_empty() {
        return Ok(0);
    }
    ctx.progress.note(&format!(
        "resuming: flying first the {} flight(s) interrupted last time (candidates {})",
        pending.len(),
        pending
            .iter()
            .map(|r| r.candidate.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    let jobs: Vec<Job> = pending
        .into_iter()
        .map(|r| Job {
            test: ctx.case.with_obstacles(r.obstacles.clone()),
            screened: Screened {
                p_fail: r.predicted_p_fail,
                raw_min_distance: r.predicted_raw_min_distance,
                ..Screened::point(
                    r.candidate,
                    r.predicted_min_distance,
                    r.predicted_flight_time_s,
                    r.status,
                )
            },
        })
        .collect();
    let progress = ctx.progress;
    progress.stage("fly interrupted", jobs.len());
    let count = AtomicUsize::new(0);
    let on_flight = |r: &FlightRecord| announce(progress, count.fetch_add(1, Ordering::Relaxed) + 1, r);
    let outcome = fly_all(
        vehicles,
        jobs,
        budget_left,
        ctx.folder,
        Journal::open(&journal_path)?,
        ctx.cancel,
        &on_flight,
    );
    for d in &outcome.dropped {
        progress.note(&format!("dropped {d}"));
    }
    if let Some(e) = outcome.errors.first() {
        return Err(CampaignError::Config(format!("journal: {e}")));
    }
    Ok(outcome.flown)
}

/// Tells the user of the `n`th flight of the stage.
fn announce(progress: &dyn Progress, n: usize, r: &FlightRecord) {
    progress.tick(n);
    progress.note(&format!(
        "flight {n}: candidate {} predicted {:.2} m, flew {} ({})",
        r.candidate,
        r.predicted_min_distance,
        r.min_distance.map_or("-".into(), |d| format!("{d:.2} m")),
        r.status
    ));
    for w in &r.warnings {
        progress.note(&format!("  warning: {w}"));
    }
}
