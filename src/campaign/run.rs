//! The campaign pipeline: sample candidates, screen them all with the LFS, fly the most severe within the
//! budget, report the failing ones best first. Resumable from its folder.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::journal::Journal;
use super::learn::Learnt;
use super::pool::Vehicle;
use super::rank::Screened;
use super::report::{Report, StageTimes, write_outputs};
use super::rounds::{RoundsInput, run_rounds};
use super::stages::{
    ENSEMBLE_SHORTLIST_PER_FLIGHT, FlightStage, Stage, apply_ensemble, ensemble_shortlist, fly_ranked, rank_unflown,
    screen_all,
};
use crate::generator::{DrawDistribution, GenerateError, Generator, GeneratorConfig};
use crate::io::write_atomic;
use crate::judge::Judge;
use crate::lfs::ensemble::EnsembleParams;
use crate::model::{ModelError, Obstacle, Spelling, TestCase};

/// Everything that defines a campaign; saved as `campaign.json` so `--resume` continues the same one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignConfig {
    /// The case study YAML.
    pub case: PathBuf,
    /// Seed of the generator.
    pub seed: u64,
    /// High-fidelity flights allowed.
    pub budget: usize,
    /// Candidates to draw and screen.
    pub candidates: usize,
    /// Only candidates predicted below this distance (metres) are flown.
    pub threshold_m: f64,
    /// Candidates overlapping an already chosen one by more than this IoU are skipped.
    pub max_iou: f64,
    /// Generator parameters.
    pub generator: GeneratorConfig,
    /// Whether tests are written with the old key spelling (`drone`/`test`).
    pub old_spelling: bool,
    /// The high-fidelity side as given (`mock` or MAVLink URLs).
    pub hfs: Vec<String>,
    /// Obstacle mode of the flights (`avoidance`, `offboard`, `mission`).
    #[serde(default = "default_mode")]
    pub mode: String,
    /// LFS motion model used for screening (`px4`, `paper`).
    #[serde(default = "default_motion")]
    pub motion: String,
    /// Clock speed of the embedded mock autopilots.
    #[serde(default = "default_mock_speed")]
    pub mock_speed: f64,
    /// The embedded mocks hold their clock for each avoidance answer (`mock_speed` is then an upper bound).
    /// Campaign files written before lockstep existed lack the key: their flights were free-running.
    #[serde(default)]
    pub mock_lockstep: bool,
    /// In lockstep, the companion plans on the pose this old (vehicle milliseconds), as a real companion's
    /// camera and planner lag behind the vehicle.
    #[serde(default = "default_mock_latency_ms")]
    pub mock_latency_ms: f64,
    /// Screen with the LFS (off: fly candidates in the order drawn, the paper's baseline without the LFS).
    #[serde(default = "default_screen")]
    pub screen: bool,
    /// The judge edition of the flights (campaign files written before editions existed were judged by 2025's).
    #[serde(default = "judge_before_editions")]
    pub judge: Judge,
    /// Re-anchor each test at the vehicle's home (`--anchor-at-vehicle-home`).
    #[serde(default)]
    pub anchor_at_vehicle_home: bool,
    /// Clock rate of the MAVLink vehicles (`--hfs-time-scale`); `None`: measured on each vehicle at connection.
    #[serde(default)]
    pub hfs_time_scale: Option<f64>,
    /// Give a flight up (LAND) after this many vehicle seconds.
    #[serde(default = "default_flight_timeout_s")]
    pub flight_timeout_s: f64,
    /// Members of the LFS ensemble run on the shortlisted candidates to rank them by expected points per
    /// minute; 0 ranks by the point prediction (campaign files written before ensembles existed).
    #[serde(default)]
    pub ensemble: usize,
    /// Learn the vehicle as the campaign flies (online calibration of the LFS, flights in rounds).
    #[serde(default)]
    pub learn: bool,
    /// With `learn`, also adapt the generator's draw distribution towards failures.
    #[serde(default)]
    pub adapt: bool,
    /// A previous campaign's folder whose `learnt.json` seeds this one.
    #[serde(default)]
    pub prior: Option<PathBuf>,
    /// The adapted generator backs off when the failing tests' diversity falls below this.
    #[serde(default = "default_min_diversity")]
    pub min_diversity: f64,
    /// With `adapt`, a child of a failing flight may overlap a flown test up to this IoU (above `max_iou`)
    /// while the failing tests would keep `min_diversity` ([`super::diversity_guard`]); `None` (campaign files
    /// written before): children obey `max_iou` like every candidate.
    #[serde(default)]
    pub child_max_iou: Option<f64>,
}

fn default_min_diversity() -> f64 {
    0.8
}

fn judge_before_editions() -> Judge {
    Judge::E2025
}

fn default_flight_timeout_s() -> f64 {
    crate::bridge::FlyOptions::default().timeout_s
}

fn default_screen() -> bool {
    true
}

fn default_mode() -> String {
    "avoidance".into()
}

fn default_motion() -> String {
    "px4".into()
}

/// Fitted against the recorded competition flights with `examples/mock_fidelity.rs` (see README, *Mock
/// autopilot fidelity*): with the mock's PX4-like braking and calibrated cruise, 0 ms gives MAE 0.81 m /
/// Spearman 0.77 on the 127 flights, 100 ms 0.92 / 0.73, 500 ms 1.06 / 0.69 (at cruise 1.5 m/s: 0 ms 0.86, 200 ms
/// 0.97). Any pose age only adds clearance, so none is modelled.
pub const DEFAULT_MOCK_LATENCY_MS: f64 = 0.0;

fn default_mock_latency_ms() -> f64 {
    DEFAULT_MOCK_LATENCY_MS
}

fn default_mock_speed() -> f64 {
    20.0
}

/// Predicts a test's flight with the low-fidelity simulator.
pub trait Screener: Sync {
    /// Predicted minimum distance (m), flight time (s) and how the simulated flight ended.
    fn screen(&self, test: &TestCase) -> (f64, f64, String);

    /// The predicted path, for plots (`None` if the screener has none).
    fn path(&self, _test: &TestCase) -> Option<crate::model::Trajectory> {
        None
    }

    /// The minimum distances of an ensemble of `n` perturbed simulations drawn from `seed` (`None` if the
    /// screener has no ensemble or the test cannot be simulated).
    fn ensemble(&self, _test: &TestCase, _n: usize, _seed: u64) -> Option<Vec<f64>> {
        None
    }

    /// The prior of `p_fail` over the members.
    fn ensemble_params(&self) -> EnsembleParams {
        EnsembleParams::default()
    }
}

/// Progress reporting for the stages.
pub trait Progress: Sync {
    /// A stage starts with `total` steps.
    fn stage(&self, name: &str, total: usize);
    /// `done` steps of the current stage are finished.
    fn tick(&self, done: usize);
    /// A line for the user.
    fn note(&self, message: &str);
}

/// Why a campaign stopped early.
#[derive(Debug, thiserror::Error)]
pub enum CampaignError {
    /// A file could not be read or written.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The generator could not place obstacles.
    #[error(transparent)]
    Generate(#[from] GenerateError),
    /// Bad settings.
    #[error("{0}")]
    Config(String),
    /// No vehicle could be reached.
    #[error("no reachable vehicle: {0}")]
    NoVehicle(String),
}

/// Runs (or resumes) a campaign in `folder`.
pub fn run_campaign(
    cfg: &CampaignConfig,
    folder: &Path,
    screener: &dyn Screener,
    mut vehicles: Vec<Box<dyn Vehicle>>,
    progress: &dyn Progress,
    cancel: &AtomicBool,
) -> Result<Report, CampaignError> {
    if cfg.budget == 0 {
        return Err(CampaignError::Config("the budget must be at least 1 flight".into()));
    }
    if cfg.candidates == 0 {
        return Err(CampaignError::Config("--candidates must be at least 1".into()));
    }
    let case = TestCase::load(&cfg.case)?;
    let spelling = if cfg.old_spelling { Spelling::Old } else { Spelling::New };
    std::fs::create_dir_all(folder.join("flights")).map_err(|source| ModelError::Io {
        path: folder.to_path_buf(),
        action: "cannot create",
        source,
    })?;
    let config_json = serde_json::to_string_pretty(cfg).unwrap_or_default();
    write_atomic(&folder.join("campaign.json"), config_json.as_bytes())?;
    let mut stages = StageTimes::default();
    // Both campaigns end the same way: the journal's flights written out as tests and reports.
    let finish = |drawn: usize, stages: StageTimes, learning: Option<&Learnt>| -> Result<Report, CampaignError> {
        let records = Journal::read(&folder.join("journal.jsonl"))?;
        Ok(write_outputs(
            folder,
            &case,
            cfg.seed,
            cfg.budget,
            drawn,
            &records,
            stages,
            spelling,
            cfg.screen,
            &|t: &TestCase| screener.path(t),
            cfg.judge,
            learning,
        )?)
    };
    if cfg.learn && cfg.screen {
        let input = RoundsInput {
            cfg,
            folder,
            case: &case,
            screener,
            progress,
            cancel,
        };
        let (learnt, drawn) = run_rounds(&input, &mut vehicles, &mut stages)?;
        return finish(drawn, stages, Some(&learnt));
    }

    let t = Instant::now();
    let generator = Generator::new(&case, cfg.generator.clone(), cfg.seed)?;
    progress.stage("sample", cfg.candidates);
    let candidates: Vec<Vec<Obstacle>> = (0..cfg.candidates as u64)
        .map(|i| generator.sample(i).map(|p| p.obstacles.to_vec()))
        .collect::<Result<_, _>>()?;
    progress.tick(cfg.candidates);
    stages.sample_s = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let ctx = Stage {
        case: &case,
        candidates: &candidates,
        folder,
        screener,
        progress,
        cancel,
    };
    let screened = if cfg.screen {
        screen_all(
            &ctx,
            0..candidates.len() as u64,
            "screening.json",
            &DrawDistribution::uniform(),
            &[],
        )?
    } else {
        // Every candidate "predicted" at 0 m: the ranking then keeps the order they were drawn in.
        (0..candidates.len() as u64)
            .map(|candidate| Screened::point(candidate, 0.0, 0.0, "unscreened".into()))
            .collect()
    };
    stages.screen_s = t.elapsed().as_secs_f64();

    let journal_path = folder.join("journal.jsonl");
    let done = Journal::read(&journal_path)?;
    let remaining = cfg.budget.saturating_sub(done.len());
    let flown: Vec<u64> = done.iter().map(|r| r.candidate).collect();
    let mut fresh: Vec<Screened> = screened.into_iter().filter(|s| !flown.contains(&s.candidate)).collect();
    if cfg.screen && cfg.ensemble > 0 {
        let t = Instant::now();
        let shortlist = remaining.saturating_mul(ENSEMBLE_SHORTLIST_PER_FLIGHT);
        let members = ensemble_shortlist(&ctx, &fresh, cfg, shortlist)?;
        apply_ensemble(&mut fresh, &members, &screener.ensemble_params());
        stages.ensemble_s = t.elapsed().as_secs_f64();
    }
    let ranked = rank_unflown(&fresh, &done, &candidates, cfg, remaining);
    if !done.is_empty() {
        progress.note(&format!(
            "resuming: {} flights already journaled, {} left in the budget",
            done.len(),
            remaining
        ));
    }
    progress.note(&format!(
        "{} of {} candidates predicted below {} m; flying {}",
        fresh.iter().filter(|s| s.min_distance < cfg.threshold_m).count(),
        cfg.candidates,
        cfg.threshold_m,
        ranked.len()
    ));

    let t = Instant::now();
    let flight = FlightStage {
        case: &case,
        candidates: &candidates,
        folder,
        progress,
        cancel,
    };
    fly_ranked(&flight, ranked, &mut vehicles, remaining)?;
    stages.fly_s = t.elapsed().as_secs_f64();
    finish(cfg.candidates, stages, None)
}

/// Whether two tests' footprints overlap by more than `max_iou`.
pub(super) fn too_similar(a: &[Obstacle], b: &[Obstacle], max_iou: f64) -> bool {
    let fa: Vec<_> = a.iter().map(Obstacle::footprint).collect();
    let fb: Vec<_> = b.iter().map(Obstacle::footprint).collect();
    crate::geometry::union_iou(&fa, &fb) > max_iou
}

#[cfg(test)]
#[path = "run_tests.rs"]
mod tests;
