//! The stages of one round, in order: draw its candidates, screen them with the LFS, rank them with what the
//! campaign learnt so far and choose the flights, then learn from the flights that landed.

use super::{ROUNDS, Ranking, Round, Rounds};
use crate::campaign::ground::candidate::{CandidateId, LfsPrediction, Lineage, Pick, is_child, unflown};
use crate::campaign::ground::error::CampaignError;
use crate::campaign::ground::stage_times::StageTimes;
use crate::campaign::learn::calibration::RoundLog;
use crate::campaign::learn::failure_counts::arm_counts;
use crate::campaign::learn::refit::{Lessons, refit};
use crate::campaign::plan::diversity_guard::DiversityGuard;
use crate::campaign::plan::draw::{DrawPlan, draw};
use crate::campaign::plan::neighbours::{self, NEAR_MISS_FLIGHT_SHARE, local_flight_share, rank_split};
use crate::campaign::plan::rank::{in_draw_order, rank_unflown};
use crate::campaign::report::user_report::plural;
use crate::campaign::screen::stages::{Stage, run_ensemble, screen_all};
use crate::campaign::store::journal::FlightRecord;
use crate::model::Obstacle;
use crate::model::competition::FAIL_BELOW_M;
use std::time::Instant;

impl Rounds<'_> {
    /// Draws round `index`'s candidates: its share of `--candidates` from the histogram, and with `adapt`
    /// children around the parents on top (as many as the round's own draws, at most [`neighbours::CHILDREN`]).
    pub(super) fn draw(&mut self, index: usize, stages: &mut StageTimes) -> Result<Round, CampaignError> {
        let cfg = self.input.cfg;
        let rounds = self.planned_rounds();
        let own = if index < rounds {
            cfg.screening.candidates * (index + 1) / rounds - cfg.screening.candidates * index / rounds
        } else {
            cfg.screening.candidates.div_ceil(rounds)
        };
        let t = Instant::now();
        // Below the diversity floor the children go on: the guard admits only those that do not lower it, so
        // the failures keep getting children for the rest of the campaign.
        let (around, lineage) = if self.adapts() {
            neighbours::parents(
                &self.journal,
                |c| self.candidates.get(c.index()).map(|x| x.unit),
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
        let planned = cfg.campaign.budget * (index + 1).min(rounds) / rounds;
        let later = cfg.campaign.budget - planned;
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

    pub(super) fn stage(&self) -> Stage<'_> {
        Stage {
            case: self.input.case,
            candidates: &self.candidates,
            folder: self.input.folder,
            screener: self.input.screener,
            progress: self.input.progress,
            cancel: self.input.cancel,
        }
    }

    /// Whether the rounds move the generator towards failures.
    pub(super) fn adapts(&self) -> bool {
        self.learning && self.input.cfg.learning.adapt
    }

    /// Screens the round's candidates (cached per round, with the distribution and the parents they came from;
    /// without learning in `screening.json`). Without screening they keep no prediction, and fly in the order
    /// they were drawn in.
    pub(super) fn screen(&mut self, round: &Round, stages: &mut StageTimes) -> Result<(), CampaignError> {
        let t = Instant::now();
        let range = round.first..round.first + round.drawn as u64;
        let cache = if self.learning {
            format!("screening_round{}.json", round.index)
        } else {
            "screening.json".to_string()
        };
        if self.input.cfg.screening.screen {
            let screened = screen_all(&self.stage(), range, &cache, &self.distribution, &round.around)?;
            for (c, s) in self.candidates[round.first as usize..].iter_mut().zip(screened) {
                c.prediction = Some(s);
            }
        }
        stages.screen_s += t.elapsed().as_secs_f64();
        Ok(())
    }

    /// Learns from every flight so far, then ranks the unflown candidates with the calibrated LFS moved towards
    /// the flights near them (and the ensembles), within the round's share of the budget.
    /// `busy` are the candidates queued or in the air, `aside` those never flown again (the replay set them
    /// aside), `committed` the flights promised ([`Self::promised`]).
    pub(super) fn rank(
        &mut self,
        round: &Round,
        (busy, aside): (&[(CandidateId, Vec<Obstacle>)], &[CandidateId]),
        committed: usize,
        stages: &mut StageTimes,
    ) -> Result<Ranking, CampaignError> {
        let cfg = self.input.cfg;
        let flown: Vec<CandidateId> = (self.journal.iter().map(|r| r.candidate))
            .chain(busy.iter().map(|(c, _)| *c))
            .chain(aside.iter().copied())
            .collect();
        let mut fresh = self.predict(&flown, stages);
        let remaining = round.planned.saturating_sub(committed);
        if cfg.screening.screen {
            stages.ensemble_s += run_ensemble(&self.stage(), &mut fresh, cfg, remaining)?;
        }
        let (ranked, share) = if cfg.screening.screen {
            let (ranked, share) = self.choose(round, &fresh, remaining, busy);
            (ranked.into_iter().map(Pick::from).collect(), share)
        } else {
            (self.unscreened(&flown, remaining, busy), 0.0)
        };
        Ok(Ranking {
            ranked,
            remaining,
            below: fresh
                .iter()
                .filter(|s| s.min_distance < cfg.screening.threshold_m)
                .count(),
            share,
            bias_m: self.calibration.bias_m(),
        })
    }

    /// The unflown candidates (not in `flown`) with their predictions: learning, the LFS's calibrated and moved
    /// towards the flights near them (learnt from every flight so far); else the LFS's own.
    fn predict(&mut self, flown: &[CandidateId], stages: &mut StageTimes) -> Vec<LfsPrediction> {
        if !self.learning {
            return unflown(&self.candidates, flown).cloned().collect();
        }
        let t = Instant::now();
        let taught = match self.carried.take() {
            Some((at, l)) if at == self.flights.len() => l,
            _ => Lessons::from(&self.start_calibration, &self.journal, &self.candidates),
        };
        self.calibration = taught.calibration.clone();
        self.surrogate = taught.kernel;
        let fresh = unflown(&self.candidates, flown)
            .map(|s| LfsPrediction {
                min_distance: taught.predict(s, &self.candidates),
                raw_min_distance: Some(s.min_distance),
                ..s.clone()
            })
            .collect();
        stages.learn_s += t.elapsed().as_secs_f64();
        fresh
    }

    /// The round's flights among `fresh`: with `adapt`, a share for the children that follows their failure
    /// rate, each admitted by the diversity guard; else the ranking's best distinct ones.
    /// `queued` stand for the flights in the fleet: the ranking keeps away from them as from the flown tests.
    pub(super) fn choose(
        &self,
        round: &Round,
        fresh: &[LfsPrediction],
        remaining: usize,
        busy: &[(CandidateId, Vec<Obstacle>)],
    ) -> (Vec<LfsPrediction>, f64) {
        let seen: Vec<&[Obstacle]> = (self.journal.iter().map(|r| r.obstacles.as_slice()))
            .chain(busy.iter().map(|(_, o)| o.as_slice()))
            .collect();
        let cfg = self.input.cfg;
        let is_arm = |c| is_child(&self.candidates, c, round.lineage);
        let (near_flown, other_flown) = arm_counts(&self.journal, is_arm);
        let share = match round.lineage {
            Lineage::Failures => local_flight_share(near_flown, other_flown),
            Lineage::NearMisses => NEAR_MISS_FLIGHT_SHARE,
        };
        if !self.adapts() {
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

    /// An unscreened campaign's flights: the candidates not in `flown`, in the order drawn.
    fn unscreened(&self, flown: &[CandidateId], remaining: usize, busy: &[(CandidateId, Vec<Obstacle>)]) -> Vec<Pick> {
        let fresh: Vec<CandidateId> = (0..self.candidates.len() as u64)
            .map(CandidateId)
            .filter(|c| !flown.contains(c))
            .collect();
        let seen: Vec<&[Obstacle]> = (self.journal.iter().map(|r| r.obstacles.as_slice()))
            .chain(busy.iter().map(|(_, o)| o.as_slice()))
            .collect();
        let max_iou = self.input.cfg.screening.max_iou;
        (in_draw_order(&fresh, &seen, &self.candidates, max_iou, remaining).into_iter())
            .map(|candidate| Pick {
                candidate,
                prediction: None,
            })
            .collect()
    }

    pub(super) fn note(&self, round: &Round, ranking: &Ranking) {
        if !self.learning {
            self.note_single(ranking);
            return;
        }
        self.input.progress.note(&format!(
            "round {} of {ROUNDS}: {} ({} near the {}), LFS bias {:+.2} m learnt from {}{}; flying {}",
            round.index + 1,
            plural(round.drawn, "candidate"),
            round.children,
            match round.lineage {
                Lineage::Failures => "failing flights",
                Lineage::NearMisses => "closest flights, none failing yet",
            },
            ranking.bias_m,
            plural(self.journal.len(), "flight"),
            self.surrogate.map_or(String::new(), |k| format!(
                ", flights' kernel h {:.2} (error {:.2} m vs LFS {:.2} m)",
                k.bandwidth, k.loo_error_m, k.lfs_error_m
            )),
            ranking.ranked.len()
        ));
        if ranking.ranked.len() < ranking.remaining {
            self.input.progress.warn(&format!(
                "round {}: only {} of the {} flights planned have a candidate predicted below --threshold {} m \
                 (and apart from the tests kept); a threshold few candidates reach leaves budget unspent",
                round.index + 1,
                ranking.ranked.len(),
                ranking.remaining,
                self.input.cfg.screening.threshold_m
            ));
        }
    }

    pub(super) fn log_round(&mut self, round: &Round, flights: usize, share: f64, bias_m: f64) {
        let adapt = self.input.cfg.learning.adapt;
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
    pub(super) fn learn(&mut self, starved: bool, stages: &mut StageTimes) {
        let t = Instant::now();
        let taught = Lessons::from(&self.start_calibration, &self.journal, &self.candidates);
        self.calibration = taught.calibration.clone();
        if self.input.cfg.learning.adapt {
            let fit = (self.input.cfg, starved);
            self.distribution = refit(&self.distribution, &self.candidates, &self.journal, &taught, fit);
        }
        self.carried = Some((self.flights.len(), taught));
        stages.learn_s += t.elapsed().as_secs_f64();
    }

    /// The one round of a campaign that does not learn; said before the flights start when the ranking cannot
    /// fill the budget, so the user need not wait for it.
    fn note_single(&self, ranking: &Ranking) {
        let (cfg, progress) = (self.input.cfg, self.input.progress);
        let (flying, remaining, below) = (ranking.ranked.len(), ranking.remaining, ranking.below);
        progress.note(&if cfg.screening.screen {
            format!(
                "{below} of {} candidates predicted below {} m; flying {flying}",
                cfg.screening.candidates, cfg.screening.threshold_m
            )
        } else {
            format!(
                "{} candidates drawn, not screened (--no-screen); flying {flying} in the order drawn",
                cfg.screening.candidates
            )
        });
        if flying < remaining {
            progress.warn(&format!(
                "{} of the {remaining} flights left in the budget will go unspent: {below} candidate(s) are \
                 predicted below --threshold {} m (or too close to one kept); raise --threshold or --candidates to \
                 use the budget",
                remaining - flying,
                cfg.screening.threshold_m
            ));
        }
    }
}
