//! The learning campaign: flights in [`ROUNDS`] rounds (and up to [`EXTRA_ROUNDS`] more while near-duplicates
//! left budget unflown). Each round is a pipeline over the campaign's [`Candidate`]s: draw ([`super::draw`]),
//! screen, learn and rank, fly, then learn from the new flights ([`super::learning`]). Before a round ranks,
//! the LFS is calibrated on every flight so far ([`super::learn`]), its predictions are moved towards the
//! flown distances of the flights near each candidate in draw space ([`super::surrogate`], a kernel chosen by
//! leave-one-out on the campaign's own flights), and the unflown candidates are re-ranked with these
//! predictions and the ensembles.
//!
//! With `adapt`, the generator moves towards failures in two ways. Some of a round's new candidates are drawn
//! in small boxes around the failing flights so far (before the first failure, around the closest near misses:
//! [`super::neighbours`]), and a share of its flights that follows their failure rate is offered to them. The
//! others come from the histogram refitted on the elites after each round ([`super::learning::refit`]). Every
//! child drawn and every candidate flown must keep the final failing tests' expected diversity above the
//! user's floor ([`DiversityGuard`]).
//!
//! The rounds fly on one [`Fleet`] whose queue stays open: with `overlap` a round is planned while the previous
//! one flies, learning from the rounds before that (one round of lag), so remote vehicles do not wait on the LFS.
//!
//! A resumed campaign replays its plan ([`super::replay`]): every round is planned again from the start, the
//! fleet takes the journaled flights in place of flying them, and only what the journal lacks is flown. Each
//! round's flights are added in memory in the order they were journaled. A test's later flights (`--confirm`) only confirm it: the rounds learn from each test's first flight, and
//! fly the tests waiting for confirmation before the round's new candidates, within the round's budget.

use std::collections::VecDeque;
use std::path::Path;
use std::sync::atomic::Ordering;
use std::time::Instant;

use super::candidate::{Candidate, Lineage, Screened, is_child};
use super::config::{CampaignError, CampaignInput};
use super::confirm::as_learnt;
use super::diversity_guard::DiversityGuard;
use super::draw::{DrawPlan, draw};
use super::failure_counts::{arm_counts, counted_failures};
use super::fleet::{Fleet, FleetSetup, run_fleet};
use super::flights::{FlightCount, FlightStage, announce, stage_jobs};
use super::journal::{FlightRecord, Journal, flights_charged};
use super::learn::{Calibration, Learnt, RoundLog};
use super::learning::{Learning, refit};
use super::neighbours::{self, NEAR_MISS_FLIGHT_SHARE, local_flight_share, rank_split};
use super::pool::Vehicle;
use super::rank::rank_unflown;
use super::replay::Replay;
use super::report::StageTimes;
use super::screening::{ENSEMBLE_SHORTLIST_PER_FLIGHT, Stage, apply_ensemble, ensemble_shortlist, screen_all};
use super::surrogate::Surrogate;
use crate::generator::Generator;
use crate::generator::adaptive::{DrawDistribution, Neighbourhood};
use crate::io::write_json;
use crate::model::competition::FAIL_BELOW_M;
use crate::model::{ModelError, Obstacle};

/// Rounds of a learning campaign (the budget and the candidates are split evenly).
pub const ROUNDS: usize = 8;
/// Rounds added (each drawing as many candidates as a planned one) while the budget is not yet flown because
/// the near-duplicate filter rejected the ranking's tail.
pub const EXTRA_ROUNDS: usize = 4;

/// Reads `folder/learnt.json` (a previous campaign's), naming the file and the field on error.
pub fn load_prior(folder: &Path) -> Result<Learnt, CampaignError> {
    let path = folder.join("learnt.json");
    let text = std::fs::read_to_string(&path).map_err(|source| ModelError::Io {
        path: path.clone(),
        action: "cannot read the prior",
        source,
    })?;
    let learnt: Learnt =
        serde_json::from_str(&text).map_err(|e| CampaignError::Config(format!("{}: {e}", path.display())))?;
    learnt
        .calibration
        .validate()
        .and_then(|()| learnt.distribution.validate())
        .map_err(|e| CampaignError::Config(format!("{}: {e}", path.display())))?;
    Ok(learnt)
}

/// Runs every round on one [`Fleet`]; returns what was learnt and the number of candidates drawn.
///
/// With `overlap`, round `r + 1` is drawn, screened and ranked from the flights of the rounds before `r` while
/// round `r` flies (one round of lag in what it learns from), so the vehicles do not wait on the LFS; without
/// it, each round is planned after the previous one landed.
pub fn run_rounds(
    input: &CampaignInput,
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    stages: &mut StageTimes,
) -> Result<(Learnt, usize), CampaignError> {
    let count = FlightCount::default();
    let mut campaign = Rounds::start(input, &count)?;
    let replay = Replay::new(&campaign.resumed, input.cfg.budget);
    let progress = input.progress;
    let tick = !input.cfg.overlap;
    let on_flight = |r: &FlightRecord| announce(progress, count.next(), r, tick);
    let setup = FleetSetup {
        folder: input.folder,
        journal: Journal::open(&input.folder.join("journal.jsonl"))?,
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
    if let Some(e) = outcome.errors.first() {
        return Err(CampaignError::Config(format!("journal: {e}")));
    }
    flown?;
    campaign.finish()
}

/// The learning campaign between rounds.
struct Rounds<'a> {
    input: &'a CampaignInput<'a>,
    /// The generator with the campaign's settings and seed.
    base: Generator,
    /// The calibration before any flight of this campaign (the prior's, carried).
    start_calibration: Calibration,
    /// The draw distribution of the next round.
    distribution: DrawDistribution,
    /// Each test once, in journal order, at its flights' mean distance: what the rounds learn from.
    journal: Vec<FlightRecord>,
    /// Every journaled flight (later flights of a test too), in journal order: what the budget counts.
    flights: Vec<FlightRecord>,
    /// Every candidate drawn, by generator index.
    candidates: Vec<Candidate>,
    log: Vec<RoundLog>,
    calibration: Calibration,
    surrogate: Option<Surrogate>,
    /// The last round's learning, reused while no flight has landed since.
    carried: Option<(usize, Learning)>,
    /// The journal as the campaign was resumed from (empty for a new one): what the replayed plan takes.
    resumed: Vec<FlightRecord>,
    /// Journaled candidates the replayed draw gave other obstacles: never flown again under their index.
    set_aside: Vec<u64>,
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
    ranked: Vec<Screened>,
    /// Flights left in the round's share of the budget.
    remaining: usize,
    /// Share of the flights offered to the children.
    share: f64,
    bias_m: f64,
}

impl<'a> Rounds<'a> {
    /// Loads the prior and the journal.
    fn start(input: &'a CampaignInput<'a>, flight_count: &'a FlightCount) -> Result<Self, CampaignError> {
        let cfg = input.cfg;
        let prior = cfg.prior.as_deref().map(load_prior).transpose()?;
        let start_calibration = prior
            .as_ref()
            .map_or_else(Calibration::default, |p| p.calibration.carried());
        let distribution = match &prior {
            Some(p) if cfg.adapt => p.distribution.clone(),
            _ => DrawDistribution::uniform(),
        };
        let resumed = Journal::read(&input.folder.join("journal.jsonl"))?;
        if !resumed.is_empty() {
            input.progress.note(&format!(
                "resuming: {} flights already journaled, {} left in the budget; the rounds are planned again \
                 and take the journaled flights rather than flying them",
                flights_charged(&resumed),
                cfg.budget.saturating_sub(flights_charged(&resumed))
            ));
        }
        Ok(Self {
            input,
            base: Generator::new(input.case, cfg.generator.clone(), cfg.seed)?,
            calibration: start_calibration.clone(),
            start_calibration,
            distribution,
            journal: Vec::new(),
            flights: Vec::new(),
            resumed,
            set_aside: Vec::new(),
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
        let lag = usize::from(cfg.overlap);
        for index in 0..ROUNDS + EXTRA_ROUNDS {
            // Past the planned rounds only while the near-duplicate filter left budget unflown.
            if index >= ROUNDS && self.promised() >= cfg.budget {
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
        self.set_aside_diverged(&round, fleet);
        self.screen(&round, stages)?;
        let busy = fleet.busy();
        let ranking = self.rank(&round, &busy, self.promised(), stages)?;
        self.note(&round, &ranking);
        let flight = FlightStage {
            case: self.input.case,
            candidates: &self.candidates,
            folder: self.input.folder,
            progress: self.input.progress,
            cancel: self.input.cancel,
            done: &self.flights,
            confirm: self.input.cfg.confirm,
            waves: self.input.cfg.repeatable_vehicles(),
        };
        let busy: Vec<u64> = busy.iter().map(|(c, _)| *c).collect();
        let jobs = stage_jobs(&flight, ranking.ranked, &busy);
        if !self.input.cfg.overlap {
            self.flight_count.new_stage();
            self.input.progress.stage("fly", jobs.len().min(ranking.remaining));
        }
        if !jobs.is_empty() && ranking.remaining > 0 && fleet.alive() == 0 {
            return Err(self.no_vehicle_left(fleet));
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
            return Err(self.no_vehicle_left(fleet));
        }
        let flights = flights_charged(&flown);
        self.flights.extend(flown);
        self.journal = as_learnt(&self.flights);
        self.log_round(&pushed.round, flights, pushed.share, pushed.bias_m);
        self.learn(flights < pushed.remaining, stages);
        Ok(())
    }

    /// A fleet with no vehicle left stops the campaign, keeping the flights journaled so far for `--resume`: a
    /// campaign that lost every vehicle must not end as a clean run that found no failing test.
    fn no_vehicle_left(&self, fleet: &Fleet) -> CampaignError {
        let dropped = fleet.dropped();
        CampaignError::NoVehicle(format!(
            "{}; the flights so far are journaled: resume with  prgenuav generate --resume {}",
            if dropped.is_empty() {
                "every vehicle was dropped in an earlier stage".to_string()
            } else {
                dropped.join("; ")
            },
            self.input.folder.display()
        ))
    }

    /// Draws round `index`'s candidates: its share of `--candidates` from the histogram, and with `adapt`
    /// children around the parents on top (as many as the round's own draws, at most [`neighbours::CHILDREN`]).
    fn draw(&mut self, index: usize, stages: &mut StageTimes) -> Result<Round, CampaignError> {
        let cfg = self.input.cfg;
        let own = if index < ROUNDS {
            cfg.candidates * (index + 1) / ROUNDS - cfg.candidates * index / ROUNDS
        } else {
            cfg.candidates.div_ceil(ROUNDS)
        };
        let t = Instant::now();
        // Below the diversity floor the children go on: the guard admits only those that do not lower it, so
        // the failures keep getting children for the rest of the campaign.
        let (around, lineage) = if cfg.adapt {
            neighbours::parents(
                &self.journal,
                |c| self.candidates.get(c as usize).map(|x| x.unit),
                FAIL_BELOW_M,
            )
        } else {
            (Vec::new(), Lineage::Failures)
        };
        let children = if around.is_empty() {
            0
        } else {
            neighbours::CHILDREN.min(own)
        };
        // Children are measured against their own lineage: a near miss's children fail at about the base rate
        // on the mock, and counting them with the failures' children would starve the latter of flights.
        let child_rate = arm_counts(&self.journal, |c| is_child(&self.candidates, c, lineage))
            .0
            .rate();
        let planned = cfg.budget * (index + 1).min(ROUNDS) / ROUNDS;
        let later = cfg.budget - planned;
        // A child must differ from its siblings and from every flown test (or come close where the failing tests'
        // diversity can afford it), and keep their expected diversity above the floor.
        let flown: &[FlightRecord] = if children == 0 { &[] } else { &self.journal };
        let mut guard = DiversityGuard::for_round(flown, FAIL_BELOW_M, cfg, later);
        let first = self.candidates.len() as u64;
        let plan = DrawPlan {
            first,
            count: own + children,
            children,
            around: &around,
            lineage,
            child_rate,
        };
        let drawn = draw(&self.base, &self.distribution, &plan, &mut guard)?;
        self.candidates.extend(drawn);
        stages.sample_s += t.elapsed().as_secs_f64();
        Ok(Round {
            index,
            first,
            drawn: own + children,
            children,
            around,
            lineage,
            planned,
            later,
        })
    }

    fn stage(&self) -> Stage<'_> {
        Stage {
            case: self.input.case,
            candidates: &self.candidates,
            folder: self.input.folder,
            screener: self.input.screener,
            progress: self.input.progress,
            cancel: self.input.cancel,
        }
    }

    /// Screens the round's candidates (cached per round, with the distribution and the parents they came from).
    fn screen(&mut self, round: &Round, stages: &mut StageTimes) -> Result<(), CampaignError> {
        let t = Instant::now();
        let range = round.first..round.first + round.drawn as u64;
        let cache = format!("screening_round{}.json", round.index);
        let screened = screen_all(&self.stage(), range, &cache, &self.distribution, &round.around)?;
        for (c, s) in self.candidates[round.first as usize..].iter_mut().zip(screened) {
            c.screened = Some(s);
        }
        stages.screen_s += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// Learns from every flight so far, then ranks the unflown candidates with the calibrated LFS moved towards
    /// the flights near them (and the ensembles), within the round's share of the budget.
    /// `busy` are the candidates queued or in the air, `committed` the flights promised ([`Self::promised`]).
    fn rank(
        &mut self,
        round: &Round,
        busy: &[(u64, Vec<Obstacle>)],
        committed: usize,
        stages: &mut StageTimes,
    ) -> Result<Ranking, CampaignError> {
        let cfg = self.input.cfg;
        let t = Instant::now();
        let taught = match self.carried.take() {
            Some((at, l)) if at == self.flights.len() => l,
            _ => Learning::from(&self.start_calibration, &self.journal, &self.candidates),
        };
        self.calibration = taught.calibration.clone();
        self.surrogate = taught.kernel;
        let flown: Vec<u64> = (self.journal.iter().map(|r| r.candidate))
            .chain(busy.iter().map(|(c, _)| *c))
            .chain(self.set_aside.iter().copied())
            .collect();
        let mut fresh: Vec<Screened> = (self.candidates.iter())
            .filter_map(|c| c.screened.as_ref())
            .filter(|s| !flown.contains(&s.candidate))
            .map(|s| Screened {
                min_distance: taught.predict(s, &self.candidates),
                raw_min_distance: Some(s.min_distance),
                ..s.clone()
            })
            .collect();
        stages.learn_s += t.elapsed().as_secs_f64();
        let remaining = round.planned.saturating_sub(committed);
        if cfg.ensemble > 0 && remaining > 0 {
            let t = Instant::now();
            let shortlist = remaining * ENSEMBLE_SHORTLIST_PER_FLIGHT;
            let members = ensemble_shortlist(&self.stage(), &fresh, cfg, shortlist)?;
            apply_ensemble(&mut fresh, &members, &self.input.screener.ensemble_params());
            stages.ensemble_s += t.elapsed().as_secs_f64();
        }
        let (ranked, share) = self.choose(round, &fresh, remaining, &FlightRecord::queued(busy));
        Ok(Ranking {
            ranked,
            remaining,
            share,
            bias_m: self.calibration.bias_m(),
        })
    }

    /// The round's flights among `fresh`: with `adapt`, a share for the children that follows their failure
    /// rate, each admitted by the diversity guard; else the ranking's best distinct ones.
    /// `queued` stand for the flights in the fleet: the ranking keeps away from them as from the flown tests.
    fn choose(
        &self,
        round: &Round,
        fresh: &[Screened],
        remaining: usize,
        queued: &[FlightRecord],
    ) -> (Vec<Screened>, f64) {
        let seen: Vec<FlightRecord> = self.journal.iter().chain(queued).cloned().collect();
        let cfg = self.input.cfg;
        let is_arm = |c| is_child(&self.candidates, c, round.lineage);
        let (near_flown, other_flown) = arm_counts(&self.journal, is_arm);
        let share = match round.lineage {
            Lineage::Failures => local_flight_share(near_flown, other_flown),
            Lineage::NearMisses => NEAR_MISS_FLIGHT_SHARE,
        };
        if !cfg.adapt {
            return (rank_unflown(fresh, &seen, &self.candidates, cfg, remaining), share);
        }
        let mut guard = DiversityGuard::for_round(&self.journal, FAIL_BELOW_M, cfg, round.later);
        let ranked = rank_split(
            fresh,
            is_arm,
            share,
            (&seen, &self.candidates),
            cfg,
            remaining,
            (&mut guard, (near_flown.rate(), other_flown.rate())),
        );
        (ranked, share)
    }

    fn note(&self, round: &Round, ranking: &Ranking) {
        self.input.progress.note(&format!(
            "round {} of {ROUNDS}: {} ({} near the {}), LFS bias {:+.2} m learnt from {}{}; flying {}",
            round.index + 1,
            super::report_user::plural(round.drawn, "candidate"),
            round.children,
            match round.lineage {
                Lineage::Failures => "failing flights",
                Lineage::NearMisses => "closest flights, none failing yet",
            },
            ranking.bias_m,
            super::report_user::plural(self.journal.len(), "flight"),
            self.surrogate.map_or(String::new(), |k| format!(
                ", flights' kernel h {:.2} (error {:.2} m vs LFS {:.2} m)",
                k.bandwidth, k.loo_error_m, k.lfs_error_m
            )),
            ranking.ranked.len()
        ));
    }

    fn log_round(&mut self, round: &Round, flights: usize, share: f64, bias_m: f64) {
        let adapt = self.input.cfg.adapt;
        self.log.push(RoundLog {
            round: round.index,
            first_candidate: round.first,
            candidates: round.drawn,
            local_candidates: (self.candidates[round.first as usize..].iter())
                .filter(|c| c.parents.is_some())
                .count(),
            local_flight_share: if adapt { share } else { 0.0 },
            near_miss_parents: round.children > 0 && round.lineage == Lineage::NearMisses,
            flights,
            bias_m,
            surrogate: self.surrogate,
            draw_means: std::array::from_fn(|d| self.distribution.mean(d)),
        });
    }

    /// Learns from every flight so far; with `adapt`, refits the histogram (backed off when the round flew
    /// fewer than its share of the budget: `starved`).
    fn learn(&mut self, starved: bool, stages: &mut StageTimes) {
        let t = Instant::now();
        let taught = Learning::from(&self.start_calibration, &self.journal, &self.candidates);
        self.calibration = taught.calibration.clone();
        if self.input.cfg.adapt {
            let fit = (self.input.cfg, starved);
            self.distribution = refit(&self.distribution, &self.candidates, &self.journal, &taught, fit);
        }
        self.carried = Some((self.flights.len(), taught));
        stages.learn_s += t.elapsed().as_secs_f64();
    }

    /// What the campaign learnt, also written to `learnt.json` (a later campaign's `--prior`).
    fn finish(self) -> Result<(Learnt, usize), CampaignError> {
        let (done, drawn) = (&self.journal, &self.candidates);
        let child_of = |lineage| move |c| is_child(drawn, c, lineage);
        let any_child = |c: u64| drawn.get(c as usize).is_some_and(|x| x.parents.is_some());
        let close = |c: u64| drawn.get(c as usize).is_some_and(|x| x.close);
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
        Ok((learnt, drawn.len()))
    }
}
#[path = "rounds_resume.rs"]
mod resume;

#[cfg(test)]
#[path = "rounds_tests.rs"]
mod tests;
