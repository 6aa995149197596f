//! From the command line and the campaign TOML to the campaign's settings: a new campaign's, or a resumed
//! campaign's stored ones once no flag asks for a different value. A resumed campaign must fly as it started
//! (its journal, learnt state and report assume it), so a flag that would change a stored setting is refused
//! by name rather than silently ignored.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::ArgMatches;
use clap::parser::ValueSource;
use prgenuav::campaign::config::Px4Backend;
use prgenuav::campaign::fly::mock_profile::{DEFAULT_PROFILE, MockProfile};
use prgenuav::campaign::fly::runner::RunnerSettings;
use prgenuav::campaign::run::{CampaignConfig, DEFAULT_MOCK_LATENCY_MS, check_counts};
use prgenuav::generator::GeneratorConfig;
use prgenuav::lfs::ensemble::MAX_MEMBERS;
use prgenuav::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};
use serde_json::Value;

use super::Args;
use crate::cli::limits;
use crate::cli::settings::{CampaignToml, Flight, Learning, Loaded, Mock, Output, Screening};
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

/// A setting given explicitly, by a flag or by the TOML file.
struct Given {
    /// `--seed`, or `screening.threshold_m`.
    name: String,
    /// The TOML file that gave it (`None`: the command line).
    file: Option<String>,
    /// A switch (`--no-learn`) is named without a value.
    switch: bool,
    /// Its key in campaign.json (`seed`, `generator.gap_m`).
    key: String,
}

/// What the command line and the TOML file ask for: the flags laid over the file.
struct Requested {
    settings: CampaignToml,
    generator: GeneratorConfig,
    given: Vec<Given>,
    out_given: bool,
}

/// Records where each setting came from while the flags are laid over the file.
struct Recorder<'a> {
    file: &'a Loaded,
    given: Vec<Given>,
}

impl Recorder<'_> {
    fn flag(&mut self, flag: &str, key: &str) {
        let switch = flag.starts_with("--no-")
            || ["--mock-free-running", "--anchor-at-vehicle-home", "--keep-ulog"].contains(&flag);
        self.given.push(Given {
            name: flag.to_string(),
            file: None,
            switch,
            key: key.to_string(),
        });
    }

    fn file_key(&mut self, file_key: &str, key: &str) {
        self.given.push(Given {
            name: file_key.to_string(),
            file: Some(self.file.name()),
            switch: false,
            key: key.to_string(),
        });
    }

    /// The flag's value if given, else the file's, recording which.
    fn pick<T>(&mut self, flag: Option<T>, file: Option<T>, (name, file_key, key): Names) -> Option<T> {
        match (flag, file) {
            (Some(v), _) if !key.is_empty() => {
                self.flag(name, key);
                Some(v)
            }
            (None, Some(v)) if !key.is_empty() => {
                self.file_key(file_key, key);
                Some(v)
            }
            (flag, file) => flag.or(file),
        }
    }
}

/// A setting's flag, its key in the TOML file, and its key in campaign.json (empty: campaign.json does not
/// store it, so a resumed campaign may change it).
type Names = (&'static str, &'static str, &'static str);

/// Reads the TOML file and lays the flags over it; `--resume` then compares, a new campaign builds.
pub fn plan(args: &Args, matches: &ArgMatches) -> anyhow::Result<Plan> {
    let file = Loaded::read(args.config.as_deref())?;
    let req = request(args, matches, &file)?;
    let mut cfg = match &args.resume {
        Some(folder) => resumed(folder, args, &req)?,
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
        limits::count("--jobs (mock.vehicles) on the embedded mocks", n, max, &why)?;
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
    let settings = lay_over(args, &file.toml, &mut r);
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

/// The flags laid over the file's sections (a flag wins).
fn lay_over(args: &Args, f: &CampaignToml, r: &mut Recorder) -> CampaignToml {
    let e = &args.expert;
    let (sc, mo) = (&f.screening, &f.mock);
    CampaignToml {
        generator: None,
        output: Output {
            spelling: r.pick(
                e.spelling,
                f.output.spelling,
                ("--spelling", "output.spelling", "old_spelling"),
            ),
        },
        screening: Screening {
            candidates: r.pick(
                args.candidates,
                sc.candidates,
                ("--candidates", "screening.candidates", "candidates"),
            ),
            threshold_m: r.pick(
                e.threshold,
                sc.threshold_m,
                ("--threshold", "screening.threshold_m", "threshold_m"),
            ),
            max_iou: r.pick(e.max_iou, sc.max_iou, ("--max-iou", "screening.max_iou", "max_iou")),
            motion: r.pick(e.motion, sc.motion, ("--motion", "screening.motion", "motion")),
            ensemble: r.pick(
                e.ensemble,
                sc.ensemble,
                ("--ensemble", "screening.ensemble", "ensemble"),
            ),
            screen: r.pick(
                e.no_screen.then_some(false),
                sc.screen,
                ("--no-screen", "screening.screen", "screen"),
            ),
        },
        mock: Mock {
            speed: r.pick(e.mock_speed, mo.speed, ("--mock-speed", "mock.speed", "mock_speed")),
            lockstep: r.pick(
                e.mock_free_running.then_some(false),
                mo.lockstep,
                ("--mock-free-running", "mock.lockstep", "mock_lockstep"),
            ),
            latency_ms: r.pick(
                e.mock_latency,
                mo.latency_ms,
                ("--mock-latency", "mock.latency_ms", "mock_latency_ms"),
            ),
            vehicles: r.pick(e.mock_vehicles, mo.vehicles, ("--mock-vehicles", "mock.vehicles", "")),
            profile: r.pick(
                e.mock_profile.clone(),
                mo.profile.clone(),
                ("--mock-profile", "mock.profile", "mock_profile"),
            ),
        },
        flight: flight(args, &f.flight, r),
        learning: learning(args, &f.learning, r),
    }
}

fn flight(args: &Args, fl: &Flight, r: &mut Recorder) -> Flight {
    let e = &args.expert;
    Flight {
        timeout_s: r.pick(
            e.timeout,
            fl.timeout_s,
            ("--timeout", "flight.timeout_s", "flight_timeout_s"),
        ),
        connect_timeout_s: r.pick(
            e.connect_timeout,
            fl.connect_timeout_s,
            ("--connect-timeout", "flight.connect_timeout_s", ""),
        ),
        connect_time_scale: r.pick(
            e.connect_time_scale,
            fl.connect_time_scale,
            ("--connect-time-scale", "flight.connect_time_scale", "hfs_time_scale"),
        ),
        anchor_at_vehicle_home: r.pick(
            e.anchor_at_vehicle_home.then_some(true),
            fl.anchor_at_vehicle_home,
            (
                "--anchor-at-vehicle-home",
                "flight.anchor_at_vehicle_home",
                "anchor_at_vehicle_home",
            ),
        ),
        confirm: r.pick(args.confirm, fl.confirm, ("--confirm", "flight.confirm", "confirm")),
        overlap: r.pick(None, fl.overlap, ("", "flight.overlap", "overlap")),
    }
}

fn learning(args: &Args, le: &Learning, r: &mut Recorder) -> Learning {
    let e = &args.expert;
    Learning {
        learn: r.pick(
            args.no_learn.then_some(false),
            le.learn,
            ("--no-learn", "learning.learn", "learn"),
        ),
        adapt: r.pick(
            e.no_adapt.then_some(false),
            le.adapt,
            ("--no-adapt", "learning.adapt", "adapt"),
        ),
        min_diversity: r.pick(
            e.min_diversity,
            le.min_diversity,
            ("--min-diversity", "learning.min_diversity", "min_diversity"),
        ),
        child_max_iou: r.pick(
            e.child_max_iou,
            le.child_max_iou,
            ("--child-max-iou", "learning.child_max_iou", "child_max_iou"),
        ),
    }
}

/// The campaign's settings: what was asked for, defaults for the rest.
fn build(case: PathBuf, budget: usize, args: &Args, req: &Requested) -> CampaignConfig {
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
        generator: req.generator.clone(),
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

/// A resumed campaign: its stored settings, once every setting asked for agrees with them.
fn resumed(folder: &Path, args: &Args, req: &Requested) -> anyhow::Result<CampaignConfig> {
    if req.out_given {
        bail!(
            "--out: a resumed campaign writes into {} (its own folder); drop --out",
            folder.display()
        );
    }
    let path = folder.join("campaign.json");
    let bytes = read_capped_no_follow(&path, MAX_READ_BYTES)?;
    let stored: CampaignConfig =
        serde_json::from_slice(&bytes).with_context(|| format!("{}: not a campaign file", path.display()))?;
    let case = match &args.case {
        // The same file under another spelling (`./missions/m.yaml`, an absolute path) is no conflict.
        Some(c) if same_file(c, &stored.case) => stored.case.clone(),
        Some(c) => c.clone(),
        None => stored.case.clone(),
    };
    let mut wanted = build(case, args.budget.unwrap_or(stored.budget), args, req);
    if let (Some(p), Some(s)) = (&wanted.prior, &stored.prior)
        && same_file(p, s)
    {
        wanted.prior = stored.prior.clone();
    }
    // Without --px4, a --speed-factor or --keep-ulog is compared with the stored instances' settings.
    if let (None, Some(p)) = (&wanted.px4, &stored.px4) {
        let f = &args.px4;
        wanted.px4 = Some(Px4Backend {
            speed_factor: f.speed_factor.unwrap_or(p.speed_factor),
            keep_ulog: f.keep_ulog || p.keep_ulog,
            build: p.build.clone(),
        });
    }
    let conflicts = conflicts(&stored, &wanted, &req.given, &path)?;
    if !conflicts.is_empty() {
        bail!("{}", conflicts.join("\n"));
    }
    // What runs is what the file says now, whoever wrote it last: shown, even with --quiet.
    eprintln!("{}", stored_summary(&stored, &path));
    Ok(stored)
}

/// The stored settings that decide what runs and where: the case, the budget, the seed, the vehicles.
fn stored_summary(cfg: &CampaignConfig, path: &Path) -> String {
    let vehicles = match (&cfg.runner, &cfg.px4) {
        (Some(t), _) => format!("runner `{t}`"),
        (None, Some(p)) => format!("PX4 build {}", p.build.display()),
        (None, None) => cfg.hfs.join(","),
    };
    format!(
        "resuming as {} says: case {}, budget {}, seed {}, vehicles {vehicles}",
        path.display(),
        cfg.case.display(),
        cfg.budget,
        cfg.seed
    )
}

/// `path` made absolute against the working folder (not resolved through links: the user's spelling stays).
fn absolute(path: &Path) -> anyhow::Result<PathBuf> {
    std::path::absolute(path).with_context(|| format!("{}: cannot make the path absolute", path.display()))
}

/// Whether `a` and `b` name one existing file (or, when either cannot be resolved, are spelled alike).
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// One line per setting asked for that differs from the stored one.
fn conflicts(
    stored: &CampaignConfig,
    wanted: &CampaignConfig,
    given: &[Given],
    path: &Path,
) -> anyhow::Result<Vec<String>> {
    let (stored, wanted) = (serde_json::to_value(stored)?, serde_json::to_value(wanted)?);
    let at = |v: &Value, key: &str| key.split('.').try_fold(v.clone(), |v, k| v.get(k).cloned());
    let mut lines = Vec::new();
    for g in given {
        let (s, w) = (at(&stored, &g.key), at(&wanted, &g.key));
        if s == w {
            continue;
        }
        let value = w.as_ref().map_or("(none)".into(), |w| asked(&g.key, w));
        let asked = match (&g.file, g.switch) {
            (Some(file), _) => format!("{} = {value} in {file}", g.name),
            (None, true) => g.name.clone(),
            (None, false) => format!("{} {value}", g.name),
        };
        lines.push(format!(
            "{asked} conflicts with {} {} stored in {}; drop it or start a new campaign",
            g.key,
            s.as_ref().map_or("(none)".into(), show),
            path.display()
        ));
    }
    Ok(lines)
}

/// The value asked for, as it was typed: campaign.json stores the spelling as `old_spelling`.
fn asked(key: &str, v: &Value) -> String {
    match (key, v) {
        ("old_spelling", Value::Bool(old)) => name_of(if *old { &Spelling::Old } else { &Spelling::New }),
        _ => show(v),
    }
}

/// A stored value as a user would type it: strings bare, lists comma-separated, ranges `MIN,MAX`.
fn show(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "(none)".into(),
        Value::Array(a) => a.iter().map(show).collect::<Vec<_>>().join(","),
        Value::Object(o) if o.len() == 2 && o.contains_key("min") && o.contains_key("max") => {
            format!("{},{}", show(&o["min"]), show(&o["max"]))
        }
        other => other.to_string(),
    }
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

#[cfg(test)]
#[path = "plan_tests.rs"]
mod tests;
