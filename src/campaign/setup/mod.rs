//! A campaign's policy before it runs: the defaults that depend on its setup (the budget, the vehicles), the
//! check of every setting against its declaration, and the vehicles that fly it ([`fleet`]). A program calling
//! [`crate::campaign::run::run_campaign`] gets the same campaign as the command line from the same request.

pub mod fleet;
pub mod resume;

use std::path::PathBuf;

use super::config::{CampaignConfig, Px4Backend, check_counts};
use super::ground::error::CampaignError;
use super::settings::mock_profile::MockProfile;
use super::settings::{Requested, check_ranges};
use crate::bridge::FlyMode;
use crate::generator::{Family, GeneratorConfig};
use crate::judge::Judge;

/// Ensemble members ranking the shortlist when the vehicles are MAVLink ones (an ensemble costs more CPU than
/// a mock flight, far less than a PX4 or hardware flight).
const LINK_ENSEMBLE: usize = 8;
/// Flights a failing test gets at most on a vehicle whose flights scatter: on PX4 a test that failed once often
/// passes when flown again, and so on the default mock profile, whose gusts are fitted to that. A mock without
/// gusts repeats every flight, so it flies each test once.
const SCATTERING_CONFIRM: usize = 3;
/// The embedded mocks' speed in `collision-prevention` mode unless `--mock-speed` says otherwise: the pilot's
/// 20 Hz sticks keep up with a mock holding its clock for them at this speed, and at the default 100 the
/// vehicle was seen never to take off (docs/collision-prevention.md#campaigns).
pub const CP_MOCK_SPEED: f64 = 20.0;

/// What a campaign is asked to fly, beyond the settings of the campaign TOML.
#[derive(Debug, Clone)]
pub struct Ask {
    /// The case study YAML.
    pub case: PathBuf,
    /// High-fidelity flights allowed.
    pub budget: usize,
    /// Seed of every random draw.
    pub seed: u64,
    /// The vehicles: `mock` or MAVLink URLs (ignored with `runner` or `px4`).
    pub connect: Vec<String>,
    /// The flight mode's name (`avoidance`, `offboard`, `mission`).
    pub mode: String,
    /// The judge edition.
    pub judge: Judge,
    /// A previous campaign's folder whose `learnt.json` seeds this one.
    pub prior: Option<PathBuf>,
    /// The runner's command template.
    pub runner: Option<String>,
    /// Flights at once, as asked.
    pub jobs: Option<usize>,
    /// PX4 SITL instances the campaign starts itself.
    pub px4: Option<Px4Backend>,
}

/// The campaign's settings: what was asked for, and the defaults for the rest, those that depend on the setup
/// included.
pub fn build(ask: &Ask, req: &Requested) -> CampaignConfig {
    let s = &req.settings;
    let hfs: Vec<String> = match (&ask.runner, &ask.px4) {
        (Some(_), _) => vec!["runner".into()],
        (None, Some(_)) => vec!["px4".into()],
        (None, None) => ask.connect.clone(),
    };
    let screen = s.screening.screen();
    let learn = screen && s.learning.learn();
    let mock = hfs == ["mock"];
    let mock_profile = s.mock.profile();
    // The profile (and its gusts) flies only in avoidance mode. An unknown profile is refused when the
    // settings are checked; here it just flies each test once.
    let mock_gust_acc_m_s2 = MockProfile::by_name(&mock_profile).map_or(0.0, |p| p.tuning.gust_acc_m_s2);
    let scatters = !mock || (ask.mode == "avoidance" && mock_gust_acc_m_s2 > 0.0);
    CampaignConfig {
        case: ask.case.clone(),
        seed: ask.seed,
        budget: ask.budget,
        candidates: s.screening.candidates.unwrap_or(ask.budget.saturating_mul(3).max(20)),
        threshold_m: s.screening.threshold_m(),
        max_iou: s.screening.max_iou(),
        generator: generator_for(&ask.mode, &req.generator),
        old_spelling: s.output.spelling() == "old",
        ensemble: s.screening.ensemble.unwrap_or(if mock { 0 } else { LINK_ENSEMBLE }),
        hfs,
        mode: ask.mode.clone(),
        motion: s.screening.motion(),
        mock_speed: match (ask.mode.as_str(), s.mock.speed) {
            ("collision-prevention", None) => CP_MOCK_SPEED,
            _ => s.mock.speed(),
        },
        mock_lockstep: s.mock.lockstep(),
        mock_latency_ms: s.mock.latency_ms(),
        mock_profile,
        mock_gust_acc_m_s2,
        screen,
        judge: ask.judge,
        anchor_at_vehicle_home: s.flight.anchor_at_vehicle_home(),
        hfs_time_scale: s.flight.connect_time_scale,
        flight_timeout_s: s.flight.timeout_s(),
        learn,
        adapt: learn && s.learning.adapt(),
        prior: ask.prior.clone(),
        min_diversity: s.learning.min_diversity(),
        child_max_iou: Some(s.learning.child_max_iou()),
        confirm: s
            .flight
            .confirm
            .unwrap_or(if scatters { SCATTERING_CONFIRM } else { 1 }),
        overlap: s.flight.overlap.unwrap_or(!mock),
        runner: ask.runner.clone(),
        jobs: ask.jobs,
        px4: ask.px4.clone(),
    }
}

/// The generator's settings for `mode`: Collision Prevention draws gates unless another family was asked for.
fn generator_for(mode: &str, asked: &GeneratorConfig) -> GeneratorConfig {
    let mut g = asked.clone();
    if mode == "collision-prevention" && g.family == Family::Paper {
        g.family = Family::Gate;
    }
    g
}

/// Checks a new campaign before anything is drawn: its counts, every setting, its vehicles and its prior.
pub fn check_new(cfg: &CampaignConfig) -> Result<(), CampaignError> {
    check(cfg)?;
    if let Some(p) = &cfg.prior {
        if !cfg.learn {
            return Err(config(
                "--prior needs a learning campaign (the settings turn learning off)",
            ));
        }
        // Refuse a bad prior before anything is sampled or flown.
        crate::campaign::conductor::load_prior(p)?;
    }
    Ok(())
}

/// Checks a new or stored campaign's settings and the vehicles it names.
pub fn check(cfg: &CampaignConfig) -> Result<(), CampaignError> {
    check_settings(cfg)?;
    if cfg.hfs.is_empty() {
        return Err(config("--connect names no vehicle"));
    }
    if cfg.hfs.len() > 1 && cfg.hfs.iter().any(|u| u == "mock") {
        return Err(config("--connect takes either `mock` or MAVLink URLs, not both"));
    }
    // Before anything is screened or flown: a typo in the fifth URL must not cost the first four flights.
    let links = cfg.runner.is_none() && cfg.px4.is_none();
    for url in cfg.hfs.iter().filter(|u| links && *u != "mock") {
        crate::bridge::LinkAddress::parse(url).map_err(|e| config(&format!("--connect: {e}")))?;
    }
    Ok(())
}

/// Checks a campaign's counts and every setting against its declaration (range, choices), naming the flag and
/// the TOML key of each; [`crate::campaign::run::run_campaign`] runs nothing else.
pub fn check_settings(cfg: &CampaignConfig) -> Result<(), CampaignError> {
    check_counts(cfg.budget, cfg.candidates)?;
    // Paths are no declared setting (and one that is not UTF-8 is refused by the run, naming it).
    let mut declared = cfg.clone();
    declared.case = PathBuf::new();
    declared.prior = None;
    declared.px4 = None;
    let stored = serde_json::to_value(&declared).map_err(|e| config(&e.to_string()))?;
    check_ranges(&stored).map_err(|e| config(&e))?;
    fly_mode(&cfg.mode)?;
    if let Err(e) = MockProfile::named(&cfg.mock_profile) {
        return Err(config(&format!("--mock-profile (mock.profile): {e}")));
    }
    if cfg.runner.is_some() && cfg.px4.is_some() {
        return Err(config(
            "--runner and --px4 are two ways to fly: give one (a runner's command may start PX4 itself)",
        ));
    }
    Ok(())
}

/// The flight mode named `name` (as campaign.json stores it).
pub fn fly_mode(name: &str) -> Result<FlyMode, CampaignError> {
    match name {
        "avoidance" => Ok(FlyMode::Avoidance),
        "offboard" => Ok(FlyMode::Offboard),
        "mission" => Ok(FlyMode::Mission),
        "collision-prevention" => Ok(FlyMode::CollisionPrevention),
        other => Err(config(&format!(
            "mode (--mode) {other:?} is not one of avoidance, offboard, mission, collision-prevention"
        ))),
    }
}

fn config(message: &str) -> CampaignError {
    CampaignError::Config(message.to_string())
}
