//! The learning campaign: flights in [`ROUNDS`] rounds (and up to [`EXTRA_ROUNDS`] more while near-duplicates
//! left budget unflown). Before each round the LFS is calibrated on every flight so far ([`super::learn`]),
//! its predictions are moved towards the flown distances of the flights near each candidate in draw space
//! ([`super::surrogate`], a kernel chosen by leave-one-out on the campaign's own flights), and the unflown
//! candidates are re-ranked with these predictions and the ensembles.
//!
//! With `adapt`, the generator moves towards failures in two ways. Some of a round's new candidates are drawn
//! in small boxes around the failing flights so far (before the first failure, around the closest near misses:
//! [`super::neighbours`]), and a share of its flights that
//! follows their failure rate is offered to them. The others come from a univariate
//! marginal distribution algorithm ([`crate::generator::adaptive`]): elites are the best [`ELITE_SHARE`] of the
//! screened candidates by prediction, plus the closest quarter of the flights and every flown failure at
//! [`FLOWN_FAILURE_WEIGHT`]; each draw's histogram moves [`FIT_RATE`] of the way to theirs and keeps
//! [`UNIFORM_FLOOR`] of uniform mass. Every child drawn and every candidate flown must keep the final failing
//! tests' expected diversity above the user's floor ([`DiversityGuard`]). When the failing tests' diversity
//! falls below it (counted from [`neighbours::MIN_FAILING_FOR_DIVERSITY`] failing tests on), the fit backs off
//! (more uniform mass, a smaller step); it also backs off when a round could not fill its share of the budget
//! (its candidates were near-duplicates of flown tests).

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use super::diversity_guard::DiversityGuard;
use super::failure_counts::{BinCount, FailureCounts};
use super::journal::{FlightRecord, Journal};
use super::learn::{Calibration, Learnt, RoundLog};
use super::neighbours::{self, Lineage};
use super::pool::Vehicle;
use super::rank::Screened;
use super::report::StageTimes;
use super::run::{CampaignConfig, CampaignError, Progress, Screener};
use super::stages::{
    ENSEMBLE_SHORTLIST_PER_FLIGHT, FlightStage, Stage, apply_ensemble, ensemble_shortlist, fly_ranked, rank_unflown,
    screen_all,
};
use super::surrogate::{Flown, Surrogate};
use crate::generator::Generator;
use crate::generator::adaptive::{DIMS, DrawDistribution, Proposal};
use crate::io::write_atomic;
use crate::judge::diversity;
use crate::model::{ModelError, Obstacle, TestCase};

/// Rounds of a learning campaign (the budget and the candidates are split evenly).
pub const ROUNDS: usize = 8;
/// Rounds added (each drawing as many candidates as a planned one) while the budget is not yet flown because
/// the near-duplicate filter rejected the ranking's tail.
pub const EXTRA_ROUNDS: usize = 4;
/// Share of the screened candidates that are elites.
pub const ELITE_SHARE: f64 = 0.1;
/// Weight of a flown elite (the closest quarter of the flights, and every failure): a truth counts more than
/// a prediction.
pub const FLOWN_FAILURE_WEIGHT: f64 = 5.0;
/// How far each fit moves the distribution towards the elites'.
pub const FIT_RATE: f64 = 0.7;
/// Uniform mass every fitted draw keeps.
pub const UNIFORM_FLOOR: f64 = 0.2;
/// The backed-off fit (rate, uniform floor) when the failures' diversity is below the user's floor or a round
/// could not fill its share of the budget.
const BACKOFF: (f64, f64) = (0.3, 0.5);
/// Below this, a flown test failed.
const FAIL_M: f64 = crate::model::competition::FAIL_BELOW_M;

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

/// The campaign's inputs that stay the same over the rounds.
pub struct RoundsInput<'a> {
    /// Settings.
    pub cfg: &'a CampaignConfig,
    /// The campaign folder.
    pub folder: &'a Path,
    /// The case study.
    pub case: &'a TestCase,
    /// The LFS.
    pub screener: &'a dyn Screener,
    /// Progress output.
    pub progress: &'a dyn Progress,
    /// Stops the campaign.
    pub cancel: &'a AtomicBool,
}

/// Runs every round; returns what was learnt and the number of candidates drawn.
pub fn run_rounds(
    input: &RoundsInput,
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    stages: &mut StageTimes,
) -> Result<(Learnt, usize), CampaignError> {
    let RoundsInput {
        cfg,
        folder,
        case,
        screener,
        progress,
        cancel,
    } = *input;
    let prior = cfg.prior.as_deref().map(load_prior).transpose()?;
    let start_calibration = prior
        .as_ref()
        .map_or_else(Calibration::default, |p| p.calibration.carried());
    let mut distribution = match &prior {
        Some(p) if cfg.adapt => p.distribution.clone(),
        _ => DrawDistribution::uniform(),
    };
    let journal_path = folder.join("journal.jsonl");
    let resumed = Journal::read(&journal_path)?.len();
    if resumed > 0 {
        progress.note(&format!(
            "resuming: {resumed} flights already journaled, {} left in the budget",
            cfg.budget.saturating_sub(resumed)
        ));
    }
    let mut candidates: Vec<Vec<Obstacle>> = Vec::new();
    let mut units: Vec<[f64; DIMS]> = Vec::new();
    // Per candidate: a child of a failing flight; a child of a near miss (drawn before the first failure).
    let mut is_local: Vec<bool> = Vec::new();
    let mut is_near_miss: Vec<bool> = Vec::new();
    // Per candidate: a child closer to a flown test than `max_iou` (admitted by the diversity guard).
    let mut is_close: Vec<bool> = Vec::new();
    let mut screened: Vec<Screened> = Vec::new();
    let mut rounds = Vec::new();
    let mut calibration = start_calibration.clone();
    let mut surrogate = None;
    let mut carried: Option<Learning> = None;
    let per_round = cfg.candidates.div_ceil(ROUNDS);
    let mut next: u64 = 0;
    for round in 0..ROUNDS + EXTRA_ROUNDS {
        // Past the planned rounds only while the near-duplicate filter left budget unflown.
        if round >= ROUNDS && Journal::read(&journal_path)?.len() >= cfg.budget {
            break;
        }
        let count = if round < ROUNDS {
            cfg.candidates * (round + 1) / ROUNDS - cfg.candidates * round / ROUNDS
        } else {
            per_round
        };
        let t = Instant::now();
        let before = Journal::read(&journal_path)?;
        // Below the diversity floor the children go on: the guard admits only those that do not lower it. (Up to
        // session 10 they paused; with close children allowed, mission 1 seed 0 fell to 0.79 at 4 failing tests
        // in round 3 and drew no child in the 5 rounds left.)
        let (around, lineage) = if cfg.adapt {
            neighbours::parents(&before, &units, FAIL_M)
        } else {
            (Vec::new(), Lineage::Failures)
        };
        // As many children as the round's own draws (a small campaign stays small), at most CHILDREN.
        let local = if around.is_empty() {
            0
        } else {
            neighbours::CHILDREN.min(count)
        };
        let count = count + local;
        let (lo, hi) = (next, next + count as u64);
        next = hi;
        let base = Generator::new(case, cfg.generator.clone(), cfg.seed)?;
        let histogram = base.clone().with_distribution(distribution.clone());
        // A child must differ from its siblings and from every flown test (or come close where the failing tests'
        // diversity can afford it), and keep their expected diversity above the floor ([`DiversityGuard`]).
        // Children are measured against their own lineage: a near miss's children fail at about the base rate
        // on the mock, and counting them with the failures' children would starve the latter of flights.
        let child_rate = arm_counts(&before, lineage.children(&is_local, &is_near_miss)).0.rate();
        // Flights the budget plans by the end of this round, and after it.
        let planned = cfg.budget * (round + 1).min(ROUNDS) / ROUNDS;
        let later = cfg.budget - planned;
        let mut rule = DiversityGuard::for_round(if local == 0 { &[] } else { &before }, FAIL_M, cfg, later);
        // Every parent's wide box, then every narrow one (`neighbours::child_box`'s order).
        let close = rule.close_children_may_fly();
        let near: Vec<Generator> = (0..2 * around.len())
            .filter_map(|j| neighbours::child_box(&around, j, close))
            .map(|n| base.clone().with_proposal(Proposal::Around(n)))
            .collect();
        for (k, i) in (lo..hi).enumerate() {
            // The round's last `local` candidates come from the parents' boxes, in turn (wide, then narrow).
            // A parent's box with no room left (or no admissible child) falls back to the histogram.
            let child = k
                .checked_sub(count - local)
                .map(|j| near[j % near.len()].sample_where(i, neighbours::CHILD_TRIES, |o| rule.admit(o, child_rate)));
            let (p, from_box) = match child {
                Some(Ok(p)) => (p, true),
                _ => (histogram.sample(i)?, false),
            };
            is_close.push(from_box && rule.last_was_close());
            candidates.push(p.obstacles.to_vec());
            units.push(p.draw.unit);
            is_local.push(from_box && lineage == Lineage::Failures);
            is_near_miss.push(from_box && lineage == Lineage::NearMisses);
        }
        stages.sample_s += t.elapsed().as_secs_f64();
        let ctx = Stage {
            case,
            candidates: &candidates,
            folder,
            screener,
            progress,
            cancel,
        };
        let t = Instant::now();
        screened.extend(screen_all(
            &ctx,
            lo..hi,
            &format!("screening_round{round}.json"),
            &distribution,
            &around,
        )?);
        stages.screen_s += t.elapsed().as_secs_f64();

        // Learn from every flight so far, then rank the unflown candidates with the calibrated LFS, moved
        // towards the flights near them.
        let t = Instant::now();
        let done = Journal::read(&journal_path)?;
        // The last round's learning still holds when no flight has landed since.
        let taught = match carried.take() {
            Some(l) if l.journaled == done.len() => l,
            _ => Learning::from(&start_calibration, &done, &units),
        };
        calibration = taught.calibration.clone();
        surrogate = taught.kernel;
        let bias = calibration.bias_m();
        let predict = |s: &Screened| taught.predict(s, &units);
        let flown: Vec<u64> = done.iter().map(|r| r.candidate).collect();
        let mut fresh: Vec<Screened> = screened
            .iter()
            .filter(|s| !flown.contains(&s.candidate))
            .map(|s| Screened {
                min_distance: predict(s),
                raw_min_distance: Some(s.min_distance),
                ..s.clone()
            })
            .collect();
        stages.learn_s += t.elapsed().as_secs_f64();
        let remaining = planned.saturating_sub(done.len());
        if cfg.ensemble > 0 && remaining > 0 {
            let t = Instant::now();
            let members = ensemble_shortlist(&ctx, &fresh, cfg, remaining * ENSEMBLE_SHORTLIST_PER_FLIGHT)?;
            apply_ensemble(&mut fresh, &members, &screener.ensemble_params());
            stages.ensemble_s += t.elapsed().as_secs_f64();
        }
        let arm = lineage.children(&is_local, &is_near_miss);
        let (near_flown, other_flown) = arm_counts(&done, arm);
        let share = match lineage {
            Lineage::Failures => neighbours::local_flight_share(near_flown, other_flown),
            Lineage::NearMisses => neighbours::NEAR_MISS_FLIGHT_SHARE,
        };
        let ranked = if cfg.adapt {
            let mut guard = DiversityGuard::for_round(&done, FAIL_M, cfg, later);
            neighbours::rank_split(
                &fresh,
                |c| arm.get(c as usize).copied().unwrap_or(false),
                share,
                (&done, &candidates),
                cfg,
                remaining,
                (&mut guard, (near_flown.rate(), other_flown.rate())),
            )
        } else {
            rank_unflown(&fresh, &done, &candidates, cfg, remaining)
        };
        progress.note(&format!(
            "round {} of {ROUNDS}: {} candidates ({local} near the {}), LFS bias {bias:+.2} m learnt \
             from {} flights{}; flying {}",
            round + 1,
            hi - lo,
            match lineage {
                Lineage::Failures => "failing flights",
                Lineage::NearMisses => "closest flights, none failing yet",
            },
            done.len(),
            surrogate.map_or(String::new(), |k| format!(
                ", flights' kernel h {:.2} (error {:.2} m vs LFS {:.2} m)",
                k.bandwidth, k.loo_error_m, k.lfs_error_m
            )),
            ranked.len()
        ));
        let t = Instant::now();
        let flight = FlightStage {
            case,
            candidates: &candidates,
            folder,
            progress,
            cancel,
        };
        let flights = fly_ranked(&flight, ranked, vehicles, remaining)?;
        stages.fly_s += t.elapsed().as_secs_f64();
        rounds.push(RoundLog {
            round,
            first_candidate: lo,
            candidates: (hi - lo) as usize,
            local_candidates: (lo as usize..hi as usize)
                .filter(|&c| is_local[c] || is_near_miss[c])
                .count(),
            local_flight_share: if cfg.adapt { share } else { 0.0 },
            near_miss_parents: local > 0 && lineage == Lineage::NearMisses,
            flights,
            bias_m: bias,
            surrogate,
            draw_means: std::array::from_fn(|d| distribution.mean(d)),
        });
        if cancel.load(std::sync::atomic::Ordering::Relaxed) {
            break;
        }
        let t = Instant::now();
        let done = Journal::read(&journal_path)?;
        let taught = Learning::from(&start_calibration, &done, &units);
        calibration = taught.calibration.clone();
        if cfg.adapt {
            // Back off when the failures grow alike (once there are enough of them to say so), or when the
            // round could not fill its share of the budget (a narrow distribution's candidates are
            // near-duplicates of the flown tests).
            let failing: Vec<Vec<Obstacle>> = done
                .iter()
                .filter(|r| r.min_distance.is_some_and(|d| d < FAIL_M))
                .map(|r| r.obstacles.clone())
                .collect();
            let starved = flights < remaining;
            let below_floor = diversity(&failing).is_some_and(|d| d < cfg.min_diversity);
            let alike = below_floor && failing.len() >= neighbours::MIN_FAILING_FOR_DIVERSITY;
            let (rate, floor) = if starved || alike {
                BACKOFF
            } else {
                (FIT_RATE, UNIFORM_FLOOR)
            };
            let predict = |s: &Screened| taught.predict(s, &units);
            distribution = distribution.fitted(&elites(&screened, &done, &units, predict), rate, floor);
        }
        carried = Some(taught);
        stages.learn_s += t.elapsed().as_secs_f64();
    }
    let done = Journal::read(&journal_path)?;
    let failure_counts = counted_failures(&done, &units);
    let (drawn_near_failures, _) = arm_counts(&done, &is_local);
    let (drawn_near_misses, _) = arm_counts(&done, &is_near_miss);
    let any_child: Vec<bool> = is_local.iter().zip(&is_near_miss).map(|(l, n)| *l || *n).collect();
    let (_, drawn_elsewhere) = arm_counts(&done, &any_child);
    let (drawn_close, _) = arm_counts(&done, &is_close);
    let learnt = Learnt {
        calibration,
        surrogate,
        distribution,
        rounds,
        failure_counts,
        drawn_near_failures,
        drawn_near_misses,
        drawn_elsewhere,
        drawn_close,
    };
    let json = serde_json::to_string_pretty(&learnt).unwrap_or_default();
    write_atomic(&folder.join("learnt.json"), json.as_bytes())?;
    Ok((learnt, candidates.len()))
}

/// The prior calibration updated with every journaled flight's raw prediction and flown distance, in order.
fn calibrated(prior: &Calibration, done: &[FlightRecord]) -> Calibration {
    let mut c = prior.clone();
    for r in done {
        if let (Some(raw), Some(flown)) = (r.predicted_raw_min_distance, r.min_distance) {
            c.observe(raw, flown);
        }
    }
    c
}

/// Flights and failures of the neighbour candidates and of the others (flights of candidates this run did
/// not draw count as others).
fn arm_counts(done: &[FlightRecord], is_local: &[bool]) -> (BinCount, BinCount) {
    let (mut near, mut other) = (BinCount::default(), BinCount::default());
    for r in done {
        if let Some(d) = r.min_distance {
            let arm = if is_local.get(r.candidate as usize).copied().unwrap_or(false) {
                &mut near
            } else {
                &mut other
            };
            arm.flights += 1;
            arm.failures += u32::from(d < FAIL_M);
        }
    }
    (near, other)
}

/// What the journal teaches: the calibration, and the flights' kernel over the flights this run drew.
struct Learning {
    /// Journal records it learnt from.
    journaled: usize,
    calibration: Calibration,
    points: Vec<Flown>,
    kernel: Option<Surrogate>,
}

impl Learning {
    fn from(start: &Calibration, done: &[FlightRecord], units: &[[f64; DIMS]]) -> Self {
        // Parallel vehicles journal a round's flights in the order they land; learning in candidate order
        // keeps the campaign a function of its seed.
        let mut done = done.to_vec();
        done.sort_by_key(|r| r.candidate);
        let done = &done[..];
        let calibration = calibrated(start, done);
        let points: Vec<Flown> = done
            .iter()
            .filter_map(|r| {
                Some(Flown {
                    unit: *units.get(r.candidate as usize)?,
                    lfs_m: calibration.predict(r.predicted_raw_min_distance?),
                    flown_m: r.min_distance.filter(|d| d.is_finite())?,
                })
            })
            .collect();
        let kernel = Surrogate::fit(&points);
        Self {
            journaled: done.len(),
            calibration,
            points,
            kernel,
        }
    }

    /// What a round ranks a screened candidate by: the calibrated LFS, moved towards the flights near it.
    fn predict(&self, s: &Screened, units: &[[f64; DIMS]]) -> f64 {
        let lfs = self.calibration.predict(s.min_distance);
        match (&self.kernel, units.get(s.candidate as usize)) {
            (Some(k), Some(u)) => k.predict(u, lfs, &self.points),
            _ => lfs,
        }
    }
}

/// Where the journaled flights failed, per draw bin (flights of candidates this run did not draw, e.g. from a
/// longer resumed run, are skipped).
fn counted_failures(done: &[FlightRecord], units: &[[f64; DIMS]]) -> FailureCounts {
    let mut m = FailureCounts::default();
    for r in done {
        if let (Some(u), Some(flown)) = (units.get(r.candidate as usize), r.min_distance) {
            m.observe(u, flown < FAIL_M);
        }
    }
    m
}

/// The elites: the best share of the screened candidates by calibrated prediction, and the flown failures.
fn elites(
    screened: &[Screened],
    done: &[FlightRecord],
    units: &[[f64; DIMS]],
    predict: impl Fn(&Screened) -> f64,
) -> Vec<([f64; DIMS], f64)> {
    let mut order: Vec<(&Screened, f64)> = screened.iter().map(|s| (s, predict(s))).collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.candidate.cmp(&b.0.candidate)));
    let take = ((order.len() as f64 * ELITE_SHARE).ceil() as usize).max(1);
    let mut out: Vec<([f64; DIMS], f64)> = order
        .iter()
        .take(take)
        .filter_map(|(s, _)| units.get(s.candidate as usize).map(|u| (*u, 1.0)))
        .collect();
    // The flights are the truth: the closest quarter of them (and every failure) weigh more than a prediction.
    let mut flown: Vec<(&FlightRecord, f64)> = done.iter().filter_map(|r| Some((r, r.min_distance?))).collect();
    flown.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.candidate.cmp(&b.0.candidate)));
    let closest = flown.len().div_ceil(4);
    for (k, (r, d)) in flown.iter().enumerate() {
        if (k < closest || *d < FAIL_M)
            && let Some(u) = units.get(r.candidate as usize)
        {
            out.push((*u, FLOWN_FAILURE_WEIGHT));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(candidate: u64, raw: f64, flown: f64) -> FlightRecord {
        crate::campaign::journal::test_record(candidate, raw, Some(flown))
    }

    #[test]
    fn calibration_replays_the_journal_and_elites_weigh_flown_failures() {
        let done = vec![record(0, 1.0, 2.0), record(1, 1.0, 1.2)];
        let c = calibrated(&Calibration::with_prior(0.0, 1.0), &done);
        // (0 + 1.0 + 0.2) / (1 + 2)
        assert!((c.bias_m() - 0.4).abs() < 1e-12);
        let screened: Vec<Screened> = (0..10)
            .map(|i| Screened::point(i, i as f64, 60.0, "landed".into()))
            .collect();
        let units: Vec<[f64; DIMS]> = (0..10).map(|i| [i as f64 / 10.0; DIMS]).collect();
        let e = elites(&screened, &done, &units, |s| c.predict(s.min_distance));
        // The best 10 % (candidate 0), then the closest quarter of the flights, which is also the one failure
        // (candidate 1, 1.2 m), at the flights' weight.
        assert_eq!(e.len(), 2);
        assert_eq!(e[0], ([0.0; DIMS], 1.0));
        assert_eq!(e[1], ([0.1; DIMS], FLOWN_FAILURE_WEIGHT));
        // The report's failure counts: candidate 1 failed in bin 0 of every draw.
        let m = counted_failures(&done, &units);
        assert_eq!((m.total.flights, m.total.failures), (2, 1));
        assert_eq!(m.draws[4][0].failures, 1);
    }

    #[test]
    fn a_prior_written_before_the_extra_draws_still_seeds_a_campaign() {
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
        // As session 11 wrote it: one row per paper draw.
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
