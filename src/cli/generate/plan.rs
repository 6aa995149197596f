//! From the command line and the campaign TOML to the campaign's settings: a new campaign's, or a resumed
//! campaign's stored ones once no flag asks for a different value. A resumed campaign must fly as it started
//! (its journal, learnt state and report assume it), so a flag that would change a stored setting is refused
//! by name rather than silently ignored.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::ArgMatches;
use clap::parser::ValueSource;
use prgenuav::campaign::fly::mock_profile::{DEFAULT_PROFILE, MockProfile};
use prgenuav::campaign::fly::runner::RunnerSettings;
use prgenuav::campaign::run::{CampaignConfig, DEFAULT_MOCK_LATENCY_MS, check_counts};

use prgenuav::generator::{Family, GeneratorConfig};
use prgenuav::lfs::ensemble::MAX_MEMBERS;

use super::Args;
use super::overlay::{Recorder, Requested};
use crate::cli::limits;
use crate::cli::settings::Loaded;
use crate::cli::values::{Mode, Motion, Spelling, name_of, parse_stored};

/// Defaults of the settings neither a flag nor the file gives.
const THRESHOLD_M: f64 = 3.0;
const MAX_IOU: f64 = 0.5;
pub(crate) const MOCK_SPEED: f64 = 100.0;
pub(crate) const FLIGHT_TIMEOUT_S: f64 = 500.0;
pub(crate) const CONNECT_TIMEOUT_S: f64 = 15.0;
const MIN_DIVERSITY: f64 = 0.8;
const CHILD_MAX_IOU: f64 = 0.85;
/// Ensemble members ranking the shortlist when the vehicles are MAVLink ones (an ensemble costs more CPU than
/// a mock flight, far less than a PX4 or hardware flight).
const LINK_ENSEMBLE: usize = 8;
/// Flights a failing test gets at most on a vehicle whose flights scatter: on PX4 a test that failed once often
/// passes when flown again, and so on the default mock profile, whose gusts are fitted to that. A mock without
/// gusts repeats every flight, so it flies each test once.
const DEFAULT_CONFIRM: usize = 3;

/// The campaign to run.
pub struct Plan {
    pub cfg: CampaignConfig,
    pub folder: PathBuf,
    /// Embedded mock autopilots at once (not stored: a resumed campaign may change it).
    pub mock_vehicles: Option<usize>,
    /// Seconds to wait for each MAVLink vehicle's first heartbeat (not stored either).
    pub connect_timeout_s: f64,
    /// With `--runner`: what its jobs share (the template is stored, the time limit not).
    pub runner: Option<RunnerSettings>,
    /// Runner jobs at once (stored: a resumed campaign keeps them unless `--jobs` is given).
    pub jobs: Option<usize>,
    /// PX4 instances at once with `--px4` (not stored either).
    pub px4_instances: Option<usize>,
}

/// Reads the TOML file and lays the flags over it; `--resume` then compares, a new campaign builds.
pub fn plan(args: &Args, matches: &ArgMatches) -> anyhow::Result<Plan> {
    let file = Loaded::read(args.config.as_deref())?;
    let req = request(args, matches, &file)?;
    let mut cfg = match &args.resume {
        Some(folder) => super::resume::resumed(folder, args, &req, &|case, budget| build(case, budget, args, &req))?,
        None => fresh(args, &req)?,
    };
    // A resumed campaign runs as many jobs as it began with, unless told otherwise.
    cfg.jobs = args.jobs.or(cfg.jobs);
    check(&cfg)?;
    if cfg.runner.is_some() && cfg.px4.is_some() {
        bail!("--runner and --px4 are two ways to fly: give one (a runner's command may start PX4 itself)");
    }
    args.px4.check(&cfg)?;
    let s = &req.settings;
    let connect_timeout_s = limits::CONNECT_TIMEOUT.check(s.flight.connect_timeout_s.unwrap_or(CONNECT_TIMEOUT_S))?;
    let mut runner = super::runner::runner_settings(&cfg, args)?;
    let at_once = super::jobs::split(&cfg, cfg.jobs, s.mock.vehicles, args.px4.instances)?;
    if let Some(n) = at_once.mock_vehicles {
        let max = limits::max_mock_vehicles();
        let why = format!("{} per core of this machine", limits::MOCKS_PER_CORE);
        let name = if s.mock.vehicles.is_some() {
            "--mock-vehicles (mock.vehicles)"
        } else {
            "--jobs on the embedded mocks"
        };
        limits::count(name, n, max, &why)?;
    }
    // Last, once every setting is known good: a new campaign claims a folder of its own.
    let folder = match &args.resume {
        Some(folder) => folder.clone(),
        None => prgenuav::campaign::store::folder::create_new(&args.out, std::time::SystemTime::now())?,
    };
    if let Some(r) = &mut runner {
        r.campaign_folder = folder.clone();
    }
    Ok(Plan {
        cfg,
        folder,
        mock_vehicles: at_once.mock_vehicles,
        connect_timeout_s,
        runner,
        jobs: at_once.runner_jobs,
        px4_instances: at_once.px4_instances,
    })
}

fn given(m: &ArgMatches, id: &str) -> bool {
    m.value_source(id) == Some(ValueSource::CommandLine)
}

fn request(args: &Args, m: &ArgMatches, file: &Loaded) -> anyhow::Result<Requested> {
    let mut r = Recorder {
        file,
        given: Vec::new(),
    };
    for (id, flag, key) in [
        ("case", "CASE", "case"),
        ("budget", "BUDGET", "budget"),
        ("seed", "--seed", "seed"),
        ("connect", "--connect", "hfs"),
        ("mode", "--mode", "mode"),
        ("judge", "--judge", "judge"),
        ("prior", "--prior", "prior"),
        ("runner", "--runner", "runner"),
        ("px4", "--px4", "px4.build"),
        ("speed_factor", "--speed-factor", "px4.speed_factor"),
        ("keep_ulog", "--keep-ulog", "px4.keep_ulog"),
    ] {
        if given(m, id) {
            r.flag(flag, key);
        }
    }
    let settings = super::overlay::lay_over(args, &file.toml, &mut r);
    let flags = args.expert.generator_flags();
    let by_flag = flags.given();
    for key in &file.generator_keys {
        if !by_flag.iter().any(|(_, k)| k == key) {
            r.file_key(&format!("generator.{key}"), &format!("generator.{key}"));
        }
    }
    for (flag, key) in by_flag {
        r.flag(flag, &format!("generator.{key}"));
    }
    Ok(Requested {
        settings,
        generator: flags.apply(file)?,
        given: r.given,
        out_given: given(m, "out"),
    })
}

/// The campaign's settings: what was asked for, defaults for the rest.
pub(super) fn build(case: PathBuf, budget: usize, args: &Args, req: &Requested) -> CampaignConfig {
    let s = &req.settings;
    let px4 = args.px4.backend();
    let hfs: Vec<String> = if args.runner.is_some() {
        vec!["runner".into()]
    } else if px4.is_some() {
        vec!["px4".into()]
    } else {
        args.connect
            .split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    };
    let screen = s.screening.screen.unwrap_or(true);
    let learn = screen && s.learning.learn.unwrap_or(true);
    let mock = hfs == ["mock"];
    let mock_profile = s.mock.profile.clone().unwrap_or_else(|| DEFAULT_PROFILE.into());
    // The profile (and its gusts) flies only in avoidance mode. An unknown profile is refused when the plan is
    // checked; here it just flies each test once.
    let mock_gust_acc_m_s2 = MockProfile::by_name(&mock_profile).map_or(0.0, |p| p.tuning.gust_acc_m_s2);
    let scatters = args.mode == crate::cli::values::Mode::Avoidance && mock_gust_acc_m_s2 > 0.0;
    CampaignConfig {
        case,
        seed: args.seed,
        budget,
        candidates: s.screening.candidates.unwrap_or(budget.saturating_mul(3).max(20)),
        threshold_m: s.screening.threshold_m.unwrap_or(THRESHOLD_M),
        max_iou: s.screening.max_iou.unwrap_or(MAX_IOU),
        generator: generator_for(args.mode, &req.generator),
        old_spelling: s.output.spelling == Some(Spelling::Old),
        ensemble: s.screening.ensemble.unwrap_or(if mock { 0 } else { LINK_ENSEMBLE }),
        hfs,
        mode: name_of(&args.mode),
        motion: name_of(&s.screening.motion.unwrap_or(Motion::Px4)),
        mock_speed: s.mock.speed.unwrap_or(MOCK_SPEED),
        mock_lockstep: s.mock.lockstep.unwrap_or(true),
        mock_latency_ms: s.mock.latency_ms.unwrap_or(DEFAULT_MOCK_LATENCY_MS),
        mock_profile: mock_profile.clone(),
        mock_gust_acc_m_s2,
        screen,
        judge: args.judge.into(),
        anchor_at_vehicle_home: s.flight.anchor_at_vehicle_home.unwrap_or(false),
        hfs_time_scale: s.flight.connect_time_scale,
        flight_timeout_s: s.flight.timeout_s.unwrap_or(FLIGHT_TIMEOUT_S),
        learn,
        adapt: learn && s.learning.adapt.unwrap_or(true),
        prior: args.prior.clone(),
        min_diversity: s.learning.min_diversity.unwrap_or(MIN_DIVERSITY),
        child_max_iou: Some(s.learning.child_max_iou.unwrap_or(CHILD_MAX_IOU)),
        confirm: s
            .flight
            .confirm
            .unwrap_or(if mock && !scatters { 1 } else { DEFAULT_CONFIRM }),
        overlap: s.flight.overlap.unwrap_or(!mock),
        runner: args.runner.clone(),
        jobs: args.jobs,
        px4,
    }
}

/// A new campaign: CASE and BUDGET required, every setting checked before anything is sampled or flown.
fn fresh(args: &Args, req: &Requested) -> anyhow::Result<CampaignConfig> {
    let (Some(case), Some(budget)) = (args.case.clone(), args.budget) else {
        bail!("give CASE.yaml and BUDGET, or --resume FOLDER");
    };
    let mut cfg = build(absolute(&case)?, budget, args, req);
    // Stored absolute, so `--resume` works from any working folder.
    cfg.prior = cfg.prior.as_deref().map(absolute).transpose()?;
    check_counts(cfg.budget, cfg.candidates)?;
    if !(0.0..=1.0).contains(&cfg.min_diversity) {
        bail!("--min-diversity (learning.min_diversity) must be within 0..1");
    }
    limits::THRESHOLD.check(cfg.threshold_m)?;
    if !(0.0..=1.0).contains(&cfg.max_iou) || !cfg.child_max_iou.is_some_and(|c| (0.0..=1.0).contains(&c)) {
        bail!("--max-iou (screening.max_iou) and --child-max-iou (learning.child_max_iou) must be within 0..1");
    }
    if let Some(p) = &cfg.prior {
        if !cfg.learn {
            bail!("--prior needs a learning campaign (the settings turn learning off)");
        }
        // Refuse a bad prior before anything is sampled or flown.
        prgenuav::campaign::plan::rounds::load_prior(p)?;
    }
    Ok(cfg)
}

/// Checks a new or stored campaign's settings, naming the flag and the TOML key of each.
fn check(cfg: &CampaignConfig) -> anyhow::Result<()> {
    parse_stored::<Motion>(&cfg.motion, "motion (--motion, screening.motion)")?;
    parse_stored::<Mode>(&cfg.mode, "mode (--mode)")?;
    limits::MOCK_SPEED.check(cfg.mock_speed)?;
    if let Some(k) = cfg.hfs_time_scale {
        limits::CONNECT_TIME_SCALE.check(k)?;
    }
    limits::FLIGHT_TIMEOUT.check(cfg.flight_timeout_s)?;
    limits::MOCK_LATENCY.check(cfg.mock_latency_ms)?;
    limits::THRESHOLD.check(cfg.threshold_m)?;
    limits::CONFIRM.check(cfg.confirm as f64)?;
    if let Err(e) = MockProfile::named(&cfg.mock_profile) {
        bail!("--mock-profile (mock.profile): {e}");
    }
    if cfg.ensemble > MAX_MEMBERS {
        bail!(
            "--ensemble (screening.ensemble) {}: at most {MAX_MEMBERS} members",
            cfg.ensemble
        );
    }
    if cfg.hfs.is_empty() {
        bail!("--connect names no vehicle");
    }
    if cfg.hfs.len() > 1 && cfg.hfs.iter().any(|u| u == "mock") {
        bail!("--connect takes either `mock` or MAVLink URLs, not both");
    }
    // Before anything is screened or flown: a typo in the fifth URL must not cost the first four flights.
    let links = cfg.runner.is_none() && cfg.px4.is_none();
    for url in cfg.hfs.iter().filter(|u| links && *u != "mock") {
        prgenuav::bridge::LinkAddress::parse(url).map_err(|e| anyhow::anyhow!("--connect: {e}"))?;
    }
    Ok(())
}

/// `path` made absolute against the working folder (not resolved through links: the user's spelling stays).
pub(super) fn absolute(path: &Path) -> anyhow::Result<PathBuf> {
    std::path::absolute(path).with_context(|| format!("{}: cannot make the path absolute", path.display()))
}

/// The generator's settings for `mode`: Collision Prevention draws gates unless another family was asked for.
fn generator_for(mode: Mode, asked: &GeneratorConfig) -> GeneratorConfig {
    let mut g = asked.clone();
    if mode == Mode::CollisionPrevention && g.family == Family::Paper {
        g.family = Family::Gate;
    }
    g
}

#[cfg(test)]
#[path = "plan_tests.rs"]
mod tests;
