//! The campaign's one pipeline. Learning, it flies in [`ROUNDS`] rounds (and up to [`EXTRA_ROUNDS`] more while near-duplicates
//! left budget unflown). Each round is a pipeline over the campaign's [`Candidate`]s: draw ([`crate::campaign::plan::draw`]),
//! screen, learn and rank, fly, then learn from the new flights ([`crate::campaign::learn::refit`]). Before a round ranks,
//! the LFS is calibrated on every flight so far ([`crate::campaign::learn::calibration`]), its predictions are moved towards the
//! flown distances of the flights near each candidate in draw space ([`crate::campaign::learn::surrogate`], a kernel chosen by
//! leave-one-out on the campaign's own flights), and the unflown candidates are re-ranked with these
//! predictions and the ensembles.
//!
//! With `adapt`, the generator moves towards failures in two ways. Some of a round's new candidates are drawn
//! in small boxes around the failing flights so far (before the first failure, around the closest near misses:
//! [`crate::campaign::plan::neighbours`]), and a share of its flights that follows their failure rate is offered to them. The
//! others come from the histogram refitted on the elites after each round ([`crate::campaign::learn::refit::refit`]). Every
//! child drawn and every candidate flown must keep the final failing tests' expected diversity above the
//! user's floor ([`crate::campaign::plan::diversity_guard::DiversityGuard`]).
//!
//! The rounds fly on one [`Fleet`] whose queue stays open: with `overlap` a round is planned while the previous
//! one flies, learning from the rounds before that (one round of lag), so remote vehicles do not wait on the LFS.
//!
//! A resumed campaign replays its plan ([`crate::campaign::fly::fleet::replay`]): every round is planned again from the start, the
//! fleet takes the journaled flights in place of flying them, and only what the journal lacks is flown. Each
//! round's flights are added in memory in the order they were journaled. A test's later flights (`--confirm`)
//! are not new tests: the rounds learn from each test once, at the mean of its flights
//! ([`crate::campaign::fly::confirm::as_learnt`]), and fly the tests waiting for confirmation before the round's
//! new candidates, within the round's budget.
//!
//! A campaign that does not learn (`--no-learn`, `--no-screen`) is the same pipeline with learning off: one
//! planned round that draws every candidate from the generator's uniform distribution, screens them into
//! `screening.json` (or predicts 0 m for each without screening, so the flights follow the draw), ranks them
//! with the LFS's own predictions and flies the budget; it writes no `learnt.json`.

use std::collections::VecDeque;
use std::path::Path;
use std::sync::atomic::Ordering;
use std::time::Instant;

use crate::campaign::fly::confirm::as_learnt;
use crate::campaign::fly::fleet::replay::Replay;
use crate::campaign::fly::fleet::{Fleet, FleetSetup, run_fleet};
use crate::campaign::fly::stage::{FlightCount, FlightStage, announce, no_vehicle_left, note_resuming, stage_jobs};
use crate::campaign::fly::vehicle::Vehicle;
use crate::campaign::ground::candidate::{Candidate, CandidateId, Lineage, Pick, is_child};
use crate::campaign::ground::error::CampaignError;
use crate::campaign::ground::input::CampaignInput;
use crate::campaign::ground::screener::Progress;
use crate::campaign::ground::stage_times::StageTimes;
use crate::campaign::learn::calibration::{Calibration, Learnt, RoundLog};
use crate::campaign::learn::failure_counts::{arm_counts, counted_failures};
use crate::campaign::learn::refit::Lessons;
use crate::campaign::learn::surrogate::Surrogate;
use crate::campaign::store::journal::{FlightRecord, Journal, flights_charged};
use crate::generator::Generator;
use crate::generator::adaptive::{DrawDistribution, Neighbourhood};
use crate::io::write_json;
use crate::model::safe_files::{MAX_READ_BYTES, read_capped};

/// Rounds of a learning campaign (the budget and the candidates are split evenly).
pub const ROUNDS: usize = 8;
/// Rounds added (each drawing as many candidates as a planned one) while the budget is not yet flown because
/// the near-duplicate filter rejected the ranking's tail.
pub const EXTRA_ROUNDS: usize = 4;

/// Reads `folder/learnt.json` (a previous campaign's), naming the file and the field on error.
pub fn load_prior(folder: &Path) -> Result<Learnt, CampaignError> {
    let path = folder.join("learnt.json");
    let bytes = read_capped(&path, MAX_READ_BYTES)?;
    let learnt: Learnt =
        serde_json::from_slice(&bytes).map_err(|e| CampaignError::Config(format!("{}: {e}", path.display())))?;
    learnt
        .calibration
        .validate()
        .and_then(|()| learnt.distribution.validate())
        .map_err(|e| CampaignError::Config(format!("{}: {e}", path.display())))?;
    Ok(learnt)
}

/// Runs every round on one [`Fleet`]; returns what was learnt (nothing without learning) and the number of
/// candidates drawn.
///
/// With `overlap`, round `r + 1` is drawn, screened and ranked from the flights of the rounds before `r` while
/// round `r` flies (one round of lag in what it learns from), so the vehicles do not wait on the LFS; without
/// it, each round is planned after the previous one landed.
pub fn run_rounds(
    input: &CampaignInput,
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    journal: &mut Journal,
    stages: &mut StageTimes,
) -> Result<(Option<Learnt>, usize), CampaignError> {
    let count = FlightCount::default();
    note_interrupted(input.progress, journal);
    let resumed = journal.charged();
    let mut campaign = Rounds::start(input, &count, &resumed)?;
    let replay = Replay::new(&resumed, input.cfg.campaign.budget);
    let progress = input.progress;
    let tick = !input.cfg.overlaps_rounds();
    let on_flight = |r: &FlightRecord| announce(progress, count.next(), r, tick);
    let setup = FleetSetup {
        folder: input.folder,
        journal,
        cancel: input.cancel,
        on_flight: &on_flight,
        waves: input.cfg.repeatable_vehicles(),
        replay,
    };
    let (flown, outcome) = run_fleet(vehicles, setup, |fleet| {
        let flown = campaign.fly_rounds(fleet, stages);
        if flown.is_err() {
            fleet.abandon();
        }
        flown
    });
    stages.add_fleet(outcome.fleet);
    for d in &outcome.dropped {
        progress.note(&format!("dropped {d}"));
    }
    if let Some(e) = outcome.errors.first() {
        return Err(CampaignError::Config(format!("journal: {e}")));
    }
    flown?;
    campaign.finish()
}

/// Tells the user which flights the last run left in the air: the replayed plan flies them again.
fn note_interrupted(progress: &dyn Progress, journal: &Journal) {
    let pending = journal.pending_interrupted();
    if pending.is_empty() {
        return;
    }
    let ids: Vec<String> = pending.iter().map(|r| r.candidate.to_string()).collect();
    progress.note(&format!(
        "resuming: the {} flight(s) interrupted last time (candidates {}) are flown again where the plan has them",
        pending.len(),
        ids.join(", ")
    ));
}

/// The campaign between rounds.
struct Rounds<'a> {
    input: &'a CampaignInput<'a>,
    /// Whether the rounds learn (calibrate, adapt): off, the campaign is one round ranked by the LFS alone.
    learning: bool,
    /// The generator with the campaign's settings and seed.
    base: Generator,
    /// The calibration before any flight of this campaign (the prior's, carried).
    start_calibration: Calibration,
    /// The draw distribution of the next round.
    distribution: DrawDistribution,
    /// Every flight the rounds have taken back from the fleet (later flights of a test too), in journal order:
    /// what the budget counts. The one list of flights the rounds keep.
    flights: Vec<FlightRecord>,
    /// `flights` as the rounds learn from them: each test once, at its flights' mean distance
    /// ([`as_learnt`]); set only from `flights`, when they change.
    journal: Vec<FlightRecord>,
    /// Every candidate drawn, by generator index.
    candidates: Vec<Candidate>,
    log: Vec<RoundLog>,
    calibration: Calibration,
    surrogate: Option<Surrogate>,
    /// The last round's learning, reused while no flight has landed since.
    carried: Option<(usize, Lessons)>,
    /// Rounds pushed to the fleet and not yet learnt from, oldest first.
    in_air: VecDeque<Pushed>,
    /// The flights' numbering in the progress lines.
    flight_count: &'a FlightCount,
}

/// A round in the fleet, with what its log needs once it has flown.
struct Pushed {
    round: Round,
    /// The flights it was planned to make.
    promised: usize,
    remaining: usize,
    share: f64,
    bias_m: f64,
}

/// One round's plan, from its draw on.
struct Round {
    index: usize,
    /// Generator index of its first candidate, and how many it drew.
    first: u64,
    drawn: usize,
    /// Children drawn around the parents.
    children: usize,
    around: Vec<Neighbourhood>,
    lineage: Lineage,
    /// Flights the budget plans by the end of this round, and after it.
    planned: usize,
    later: usize,
}

/// A round's ranking and what it was made with.
struct Ranking {
    ranked: Vec<Pick>,
    /// Flights left in the round's share of the budget.
    remaining: usize,
    /// Unflown candidates predicted below the threshold.
    below: usize,
    /// Share of the flights offered to the children.
    share: f64,
    bias_m: f64,
}

impl<'a> Rounds<'a> {
    /// Loads the prior and the journal.
    /// `resumed`: the journal's charged flights (the replay serves them).
    fn start(
        input: &'a CampaignInput<'a>,
        flight_count: &'a FlightCount,
        resumed: &[FlightRecord],
    ) -> Result<Self, CampaignError> {
        let cfg = input.cfg;
        let learning = cfg.learns();
        // Without learning the one round draws from the uniform distribution and ranks by the LFS alone.
        let prior = (cfg.campaign.prior.as_deref().filter(|_| learning))
            .map(load_prior)
            .transpose()?;
        let start_calibration = prior
            .as_ref()
            .map_or_else(Calibration::default, |p| p.calibration.carried());
        let distribution = match &prior {
            Some(p) if cfg.learning.adapt => p.distribution.clone(),
            _ => DrawDistribution::uniform(),
        };
        let how = "; the rounds are planned again and take the journaled flights rather than flying them";
        note_resuming(input.progress, resumed, cfg.campaign.budget, how);
        Ok(Self {
            input,
            learning,
            base: Generator::new(input.case, cfg.generator.clone(), cfg.campaign.seed)?,
            calibration: start_calibration.clone(),
            start_calibration,
            distribution,
            journal: Vec::new(),
            flights: Vec::new(),
            candidates: Vec::new(),
            log: Vec::new(),
            surrogate: None,
            carried: None,
            in_air: VecDeque::new(),
            flight_count,
        })
    }

    /// Plans every round and flies it on `fleet`, learning from each round once it has landed (with `overlap`,
    /// after the next round is planned).
    fn fly_rounds(&mut self, fleet: &Fleet, stages: &mut StageTimes) -> Result<(), CampaignError> {
        let cfg = self.input.cfg;
        let lag = usize::from(cfg.overlaps_rounds());
        let planned = self.planned_rounds();
        let extra = if self.learning { EXTRA_ROUNDS } else { 0 };
        for index in 0..planned + extra {
            // Past the planned rounds only while the near-duplicate filter left budget unflown.
            if index >= planned && self.promised() >= cfg.campaign.budget {
                break;
            }
            if self.input.cancel.load(Ordering::Relaxed) {
                break;
            }
            self.plan(index, fleet, stages)?;
            while self.in_air.len() > lag {
                self.absorb(fleet, stages)?;
            }
        }
        while !self.in_air.is_empty() {
            self.absorb(fleet, stages)?;
        }
        self.keep_unreplayed(fleet);
        Ok(())
    }

    /// Round `index`: draw, screen and rank (from the flights learnt so far), then push its flights.
    fn plan(&mut self, index: usize, fleet: &Fleet, stages: &mut StageTimes) -> Result<(), CampaignError> {
        let round = self.draw(index, stages)?;
        self.check_drawn(&round, fleet)?;
        self.screen(&round, stages)?;
        let (busy, aside) = (fleet.busy(), fleet.set_aside());
        let ranking = self.rank(&round, (&busy, &aside), self.promised(), stages)?;
        self.note(&round, &ranking);
        let flight = FlightStage::new(self.input, &self.candidates, &self.flights);
        let busy: Vec<CandidateId> = busy.iter().map(|(c, _)| *c).collect();
        let jobs = stage_jobs(&flight, ranking.ranked, &busy);
        if !self.input.cfg.overlaps_rounds() {
            self.flight_count.new_stage();
            self.input.progress.stage("fly", jobs.len().min(ranking.remaining));
        }
        if !jobs.is_empty() && ranking.remaining > 0 && fleet.alive() == 0 {
            return Err(no_vehicle_left(self.input.folder, &fleet.dropped()));
        }
        let promised = jobs.len().min(ranking.remaining);
        fleet.push(index, jobs, round.planned);
        self.in_air.push_back(Pushed {
            promised,
            round,
            remaining: ranking.remaining,
            share: ranking.share,
            bias_m: ranking.bias_m,
        });
        Ok(())
    }

    /// The flights promised when a round is planned: those of the rounds learnt from, and those the rounds in the
    /// air were planned to make. Unlike the fleet's count, it does not depend on how many flights of those rounds
    /// have landed, so a replayed plan asks for what the uninterrupted one did.
    fn promised(&self) -> usize {
        flights_charged(&self.flights) + self.in_air.iter().map(|p| p.promised).sum::<usize>()
    }

    /// Waits for the oldest round in the air to land, then learns from it.
    fn absorb(&mut self, fleet: &Fleet, stages: &mut StageTimes) -> Result<(), CampaignError> {
        let Some(pushed) = self.in_air.pop_front() else {
            return Ok(());
        };
        let t = Instant::now();
        let flown = fleet.wait_round(pushed.round.index);
        stages.fly_s += t.elapsed().as_secs_f64();
        if fleet.alive() == 0 && !self.input.cancel.load(Ordering::Relaxed) && fleet.journal_error().is_none() {
            return Err(no_vehicle_left(self.input.folder, &fleet.dropped()));
        }
        let flights = flights_charged(&flown);
        self.flights.extend(flown);
        self.journal = as_learnt(&self.flights);
        if self.learning {
            self.log_round(&pushed.round, flights, pushed.share, pushed.bias_m);
            self.learn(flights < pushed.remaining, stages);
        }
        Ok(())
    }

    /// The rounds planned: one without learning.
    fn planned_rounds(&self) -> usize {
        if self.learning { ROUNDS } else { 1 }
    }

    /// What the campaign learnt, also written to `learnt.json` (a later campaign's `--prior`).
    fn finish(self) -> Result<(Option<Learnt>, usize), CampaignError> {
        let (done, drawn) = (&self.journal, &self.candidates);
        if !self.learning {
            return Ok((None, drawn.len()));
        }
        let child_of = |lineage| move |c| is_child(drawn, c, lineage);
        let any_child = |c: CandidateId| drawn.get(c.index()).is_some_and(|x| x.parents.is_some());
        let close = |c: CandidateId| drawn.get(c.index()).is_some_and(|x| x.close);
        let learnt = Learnt {
            calibration: self.calibration,
            surrogate: self.surrogate,
            distribution: self.distribution,
            rounds: self.log,
            failure_counts: counted_failures(done, drawn),
            drawn_near_failures: arm_counts(done, child_of(Lineage::Failures)).0,
            drawn_near_misses: arm_counts(done, child_of(Lineage::NearMisses)).0,
            drawn_elsewhere: arm_counts(done, any_child).1,
            drawn_close: arm_counts(done, close).0,
        };
        write_json(&self.input.folder.join("learnt.json"), &learnt, true)?;
        Ok((Some(learnt), drawn.len()))
    }
}
mod resume;
mod round;

#[cfg(test)]
mod tests;
