//! The static campaign (`--no-learn`, or without screening): every candidate drawn and screened at once, the
//! budget flown in one pass down the ranking. It shares the stage functions of the learning campaign's rounds
//! but not their loop: its screening cache (`screening.json`), its journal records (no calibrated prediction
//! beside the LFS's own) and its unscreened mode (flights in draw order) must stay as they are, so resumes of
//! existing campaign folders and the paper's baseline keep their meaning.

use std::time::Instant;

use crate::campaign::candidate::{Candidate, CandidateId, Screened, check_journaled_as_drawn, unflown};
use crate::campaign::config::{CampaignError, CampaignInput};
use crate::campaign::fly::stage::{FlightStage, fly_ranked, note_resuming};
use crate::campaign::fly::vehicle::Vehicle;
use crate::campaign::plan::rank::rank_unflown;
use crate::campaign::report::outputs::StageTimes;
use crate::campaign::screen::stages::{Stage, run_ensemble, screen_all};
use crate::campaign::store::journal::{FlightRecord, Journal, flights_charged};
use crate::generator::{DrawDistribution, Generator};

/// Draws, screens, ranks and flies; returns the number of candidates drawn.
pub fn run_static(
    input: &CampaignInput,
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    journal: &mut Journal,
    stages: &mut StageTimes,
) -> Result<usize, CampaignError> {
    let t = Instant::now();
    let mut candidates = draw_all(input)?;
    let all = CandidateId(0)..CandidateId(u64::MAX);
    check_journaled_as_drawn(journal.records(), &candidates, all, journal.path()).map_err(CampaignError::Config)?;
    stages.sample_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    screen(input, &mut candidates)?;
    stages.screen_s = t.elapsed().as_secs_f64();
    let done = journal.charged();
    let (ranked, remaining) = rank(input, &candidates, &done, stages)?;
    let t = Instant::now();
    let flight = FlightStage::new(input, &candidates, &done);
    let (_, fleet) = fly_ranked(&flight, ranked, vehicles, journal, remaining)?;
    stages.fly_s = t.elapsed().as_secs_f64();
    stages.add_fleet(fleet);
    Ok(input.cfg.candidates)
}

/// Every candidate, from the generator's uniform distribution.
fn draw_all(input: &CampaignInput) -> Result<Vec<Candidate>, CampaignError> {
    let cfg = input.cfg;
    let generator = Generator::new(input.case, cfg.generator.clone(), cfg.seed)?;
    input.progress.stage("sample", cfg.candidates);
    let candidates = (0..cfg.candidates as u64)
        .map(|i| {
            generator
                .sample(i)
                .map(|p| Candidate::drawn(p.obstacles.to_vec(), p.draw.unit))
        })
        .collect::<Result<_, _>>()?;
    input.progress.tick(cfg.candidates);
    Ok(candidates)
}

fn stage<'a>(input: &CampaignInput<'a>, candidates: &'a [Candidate]) -> Stage<'a> {
    Stage {
        case: input.case,
        candidates,
        folder: input.folder,
        screener: input.screener,
        progress: input.progress,
        cancel: input.cancel,
    }
}

/// Screens every candidate; without screening each is "predicted" at 0 m, so the ranking keeps the order they
/// were drawn in.
fn screen(input: &CampaignInput, candidates: &mut [Candidate]) -> Result<(), CampaignError> {
    let n = candidates.len() as u64;
    let screened: Vec<Screened> = if input.cfg.screen {
        let uniform = DrawDistribution::uniform();
        screen_all(&stage(input, candidates), 0..n, "screening.json", &uniform, &[])?
    } else {
        (0..n)
            .map(|i| Screened::point(CandidateId(i), 0.0, 0.0, "unscreened".into()))
            .collect()
    };
    for (c, s) in candidates.iter_mut().zip(screened) {
        c.screened = Some(s);
    }
    Ok(())
}

/// The unflown candidates to fly within what the budget has left after the journaled flights `done`, and that
/// many.
fn rank(
    input: &CampaignInput,
    candidates: &[Candidate],
    done: &[FlightRecord],
    stages: &mut StageTimes,
) -> Result<(Vec<Screened>, usize), CampaignError> {
    let cfg = input.cfg;
    let remaining = cfg.budget.saturating_sub(flights_charged(done));
    let flown: Vec<CandidateId> = done.iter().map(|r| r.candidate).collect();
    let mut fresh: Vec<Screened> = unflown(candidates, &flown).cloned().collect();
    if cfg.screen {
        stages.ensemble_s += run_ensemble(&stage(input, candidates), &mut fresh, cfg, remaining)?;
    }
    let ranked = rank_unflown(&fresh, done, candidates, cfg, remaining);
    note_resuming(input.progress, done, cfg.budget, "");
    let below = fresh.iter().filter(|s| s.min_distance < cfg.threshold_m).count();
    input.progress.note(&format!(
        "{below} of {} candidates predicted below {} m; flying {}",
        cfg.candidates,
        cfg.threshold_m,
        ranked.len()
    ));
    if ranked.len() < remaining {
        input.progress.warn(&unspent_warning(
            remaining - ranked.len(),
            remaining,
            below,
            cfg.threshold_m,
        ));
    }
    Ok((ranked, remaining))
}

/// Said before the flights start when the ranking cannot fill the budget: a threshold nobody reaches flies
/// nothing, and the user should know before waiting for it.
fn unspent_warning(unspent: usize, remaining: usize, below: usize, threshold_m: f64) -> String {
    format!(
        "{unspent} of the {remaining} flights left in the budget will go unspent: {below} candidate(s) are predicted \
         below --threshold {threshold_m} m (or too close to one kept); raise --threshold or --candidates to use \
         the budget"
    )
}
