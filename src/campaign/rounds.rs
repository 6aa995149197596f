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
//! The journal is read once; each round's flights are added to it in memory in the order they were journaled.
//! A test's later flights (`--confirm`) only confirm it: the rounds learn from each test's first flight, and
//! fly the tests waiting for confirmation before the round's new candidates, within the round's budget.

use std::path::Path;
use std::sync::atomic::Ordering;
use std::time::Instant;

use super::candidate::{Candidate, Lineage, Screened, is_child};
use super::config::{CampaignError, CampaignInput};
use super::confirm::first_flights;
use super::diversity_guard::DiversityGuard;
use super::draw::{DrawPlan, draw};
use super::failure_counts::{arm_counts, counted_failures};
use super::flights::{FlightStage, fly_ranked};
use super::journal::{FlightRecord, Journal, flights_charged};
use super::learn::{Calibration, Learnt, RoundLog};
use super::learning::{Learning, refit};
use super::neighbours::{self, NEAR_MISS_FLIGHT_SHARE, local_flight_share, rank_split};
use super::pool::Vehicle;
use super::rank::rank_unflown;
use super::report::StageTimes;
use super::screening::{ENSEMBLE_SHORTLIST_PER_FLIGHT, Stage, apply_ensemble, ensemble_shortlist, screen_all};
use super::surrogate::Surrogate;
use crate::generator::Generator;
use crate::generator::adaptive::{DrawDistribution, Neighbourhood};
use crate::io::write_json;
use crate::model::ModelError;
use crate::model::competition::FAIL_BELOW_M;

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

/// Runs every round; returns what was learnt and the number of candidates drawn.
pub fn run_rounds(
    input: &CampaignInput,
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    stages: &mut StageTimes,
) -> Result<(Learnt, usize), CampaignError> {
    let mut campaign = Rounds::start(input)?;
    for index in 0..ROUNDS + EXTRA_ROUNDS {
        // Past the planned rounds only while the near-duplicate filter left budget unflown.
        if index >= ROUNDS && flights_charged(&campaign.flights) >= input.cfg.budget {
            break;
        }
        if !campaign.round(index, vehicles, stages)? {
            break;
        }
    }
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
    /// Each test's first flight, in journal order: what the rounds learn from.
    journal: Vec<FlightRecord>,
    /// Every journaled flight (later flights of a test too), in journal order: what the budget counts.
    flights: Vec<FlightRecord>,
    /// Every candidate drawn, by generator index.
    candidates: Vec<Candidate>,
    log: Vec<RoundLog>,
    calibration: Calibration,
    surrogate: Option<Surrogate>,
    /// The last round's learning, reused while no flight has landed since.
    carried: Option<Learning>,
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
    fn start(input: &'a CampaignInput<'a>) -> Result<Self, CampaignError> {
        let cfg = input.cfg;
        let prior = cfg.prior.as_deref().map(load_prior).transpose()?;
        let start_calibration = prior
            .as_ref()
            .map_or_else(Calibration::default, |p| p.calibration.carried());
        let distribution = match &prior {
            Some(p) if cfg.adapt => p.distribution.clone(),
            _ => DrawDistribution::uniform(),
        };
        let flights = Journal::read(&input.folder.join("journal.jsonl"))?;
        if !flights.is_empty() {
            input.progress.note(&format!(
                "resuming: {} flights already journaled, {} left in the budget",
                flights_charged(&flights),
                cfg.budget.saturating_sub(flights_charged(&flights))
            ));
        }
        Ok(Self {
            input,
            base: Generator::new(input.case, cfg.generator.clone(), cfg.seed)?,
            calibration: start_calibration.clone(),
            start_calibration,
            distribution,
            journal: first_flights(&flights),
            flights,
            candidates: Vec::new(),
            log: Vec::new(),
            surrogate: None,
            carried: None,
        })
    }

    /// Round `index`: draw, screen, rank, fly, learn. Returns false when the campaign was cancelled.
    fn round(
        &mut self,
        index: usize,
        vehicles: &mut Vec<Box<dyn Vehicle>>,
        stages: &mut StageTimes,
    ) -> Result<bool, CampaignError> {
        let round = self.draw(index, stages)?;
        self.screen(&round, stages)?;
        let ranking = self.rank(&round, stages)?;
        self.note(&round, &ranking);
        let t = Instant::now();
        let flight = FlightStage {
            case: self.input.case,
            candidates: &self.candidates,
            folder: self.input.folder,
            progress: self.input.progress,
            cancel: self.input.cancel,
            done: &self.flights,
            confirm: self.input.cfg.confirm,
        };
        let flown = fly_ranked(&flight, ranking.ranked, vehicles, ranking.remaining)?;
        let flights = flights_charged(&flown);
        self.journal.extend(first_flights(&flown));
        self.flights.extend(flown);
        stages.fly_s += t.elapsed().as_secs_f64();
        self.log_round(&round, flights, ranking.share, ranking.bias_m);
        if self.input.cancel.load(Ordering::Relaxed) {
            return Ok(false);
        }
        self.learn(flights < ranking.remaining, stages);
        Ok(true)
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
    fn rank(&mut self, round: &Round, stages: &mut StageTimes) -> Result<Ranking, CampaignError> {
        let cfg = self.input.cfg;
        let t = Instant::now();
        let taught = match self.carried.take() {
            Some(l) if l.journaled == self.journal.len() => l,
            _ => Learning::from(&self.start_calibration, &self.journal, &self.candidates),
        };
        self.calibration = taught.calibration.clone();
        self.surrogate = taught.kernel;
        let flown: Vec<u64> = self.journal.iter().map(|r| r.candidate).collect();
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
        let remaining = round.planned.saturating_sub(flights_charged(&self.flights));
        if cfg.ensemble > 0 && remaining > 0 {
            let t = Instant::now();
            let shortlist = remaining * ENSEMBLE_SHORTLIST_PER_FLIGHT;
            let members = ensemble_shortlist(&self.stage(), &fresh, cfg, shortlist)?;
            apply_ensemble(&mut fresh, &members, &self.input.screener.ensemble_params());
            stages.ensemble_s += t.elapsed().as_secs_f64();
        }
        let (ranked, share) = self.choose(round, &fresh, remaining);
        Ok(Ranking {
            ranked,
            remaining,
            share,
            bias_m: self.calibration.bias_m(),
        })
    }

    /// The round's flights among `fresh`: with `adapt`, a share for the children that follows their failure
    /// rate, each admitted by the diversity guard; else the ranking's best distinct ones.
    fn choose(&self, round: &Round, fresh: &[Screened], remaining: usize) -> (Vec<Screened>, f64) {
        let cfg = self.input.cfg;
        let is_arm = |c| is_child(&self.candidates, c, round.lineage);
        let (near_flown, other_flown) = arm_counts(&self.journal, is_arm);
        let share = match round.lineage {
            Lineage::Failures => local_flight_share(near_flown, other_flown),
            Lineage::NearMisses => NEAR_MISS_FLIGHT_SHARE,
        };
        if !cfg.adapt {
            return (
                rank_unflown(fresh, &self.journal, &self.candidates, cfg, remaining),
                share,
            );
        }
        let mut guard = DiversityGuard::for_round(&self.journal, FAIL_BELOW_M, cfg, round.later);
        let ranked = rank_split(
            fresh,
            is_arm,
            share,
            (&self.journal, &self.candidates),
            cfg,
            remaining,
            (&mut guard, (near_flown.rate(), other_flown.rate())),
        );
        (ranked, share)
    }

    fn note(&self, round: &Round, ranking: &Ranking) {
        self.input.progress.note(&format!(
            "round {} of {ROUNDS}: {} candidates ({} near the {}), LFS bias {:+.2} m learnt from {} flights{}; \
             flying {}",
            round.index + 1,
            round.drawn,
            round.children,
            match round.lineage {
                Lineage::Failures => "failing flights",
                Lineage::NearMisses => "closest flights, none failing yet",
            },
            ranking.bias_m,
            self.journal.len(),
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
        self.carried = Some(taught);
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
#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::failure_counts::{BinCount, FailureCounts};
    use crate::generator::adaptive::DIMS;

    #[test]
    fn a_prior_with_only_the_paper_draws_still_seeds_a_campaign() {
        let dir = tempfile::tempdir().unwrap();
        let mut distribution = DrawDistribution::uniform();
        distribution.weights[2] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0];
        let mut counts = FailureCounts::default();
        counts.observe(&[0.9; DIMS], true);
        let l = Learnt {
            calibration: Calibration::with_prior(0.7, 12.0),
            surrogate: None,
            distribution,
            rounds: Vec::new(),
            failure_counts: counts,
            drawn_near_failures: BinCount::default(),
            drawn_near_misses: BinCount::default(),
            drawn_elsewhere: BinCount::default(),
            drawn_close: BinCount::default(),
        };
        // A prior learnt before the generator had extra draws: one row per paper draw.
        let mut json = serde_json::to_value(&l).unwrap();
        for (field, rows) in [("distribution", "weights"), ("failure_counts", "draws")] {
            let rows = json[field][rows].as_array_mut().unwrap();
            rows.truncate(crate::generator::adaptive::PAPER_DIMS);
        }
        std::fs::write(dir.path().join("learnt.json"), json.to_string()).unwrap();
        let read = load_prior(dir.path()).unwrap();
        assert_eq!(read.distribution, l.distribution, "the extra draws start uniform");
        assert_eq!(read.failure_counts.draws[2], l.failure_counts.draws[2]);
        assert_eq!(
            read.failure_counts.draws[6],
            [BinCount::default(); 5],
            "no counts for the extra draws"
        );
        assert_eq!(read.calibration, l.calibration);
    }

    #[test]
    fn a_bad_prior_file_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        assert!(load_prior(dir.path()).unwrap_err().to_string().contains("learnt.json"));
        let mut l = Learnt {
            calibration: Calibration::default(),
            surrogate: None,
            distribution: DrawDistribution::uniform(),
            rounds: Vec::new(),
            failure_counts: FailureCounts::default(),
            drawn_near_failures: BinCount::default(),
            drawn_near_misses: BinCount::default(),
            drawn_elsewhere: BinCount::default(),
            drawn_close: BinCount::default(),
        };
        l.calibration.prior_flights = -3.0;
        std::fs::write(dir.path().join("learnt.json"), serde_json::to_string(&l).unwrap()).unwrap();
        let e = load_prior(dir.path()).unwrap_err().to_string();
        assert!(e.contains("learnt.json") && e.contains("prior_flights"), "{e}");
    }
}
