//! `prgenuav evaluate FOLDER [--runs 5] [--top N]`: flies every test of a suite several times on the same
//! backends as `generate` and writes the 2026 evaluation into FOLDER/evaluation/ (docs/evaluate.md).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::time::Instant;

use anyhow::{Context, bail};
use prgenuav::campaign::evaluation::flying::{EvaluateSetup, Evaluated, evaluate_by_flying};
use prgenuav::campaign::evaluation::report;
use prgenuav::campaign::evaluation::{RUNS_2026, SIMILAR_BELOW_M};
use prgenuav::campaign::fly::runner::{DEFAULT_JOB_TIMEOUT_S, RunnerSettings, Template};
use prgenuav::campaign::run::CampaignConfig;
use prgenuav::campaign::settings::keys::flags::JOBS;
use prgenuav::campaign::settings::{Flight, Requested, find};
use prgenuav::campaign::setup::fleet::{AtOnce, split};
use prgenuav::campaign::setup::{self, Ask};
use prgenuav::campaign::store::journal::FlightRecord;
use prgenuav::model::Spelling;
use prgenuav::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};

use super::generate::plan::Plan;
use super::generate::px4::Px4Flags;
use super::generate::vehicles;
use super::limits;
use super::values::{JudgeEdition, Mode, name_of};

/// Arguments of `evaluate`.
#[derive(Debug, clap::Args)]
pub struct EvaluateArgs {
    /// The suite: a `generate` output folder or any folder of Aerialist test YAMLs, best first (test_N.yaml
    /// by N; without any, every .yaml by name).
    folder: PathBuf,
    /// Flights per test (1 to 20; the 2026 competition flies 5).
    #[arg(long, default_value_t = RUNS_2026)]
    runs: usize,
    /// Only the first N tests (the others are not read).
    #[arg(long, value_name = "N")]
    top: Option<usize>,
    /// Two tests are too similar when the DTW distance of their average trajectories is below this (metres,
    /// summed over the alignment; docs/evaluate.md).
    #[arg(long, value_name = "METRES", default_value_t = SIMILAR_BELOW_M)]
    similar_below: f64,
    /// The vehicles: `mock` (embedded mock autopilots, the suite's campaign settings if it has
    /// campaign.json) or MAVLink URLs separated by commas.
    #[arg(long, value_name = "mock|URL,...", default_value = "mock")]
    connect: String,
    /// Fly each test as a job of an existing engine (as `generate --runner`, docs/runners.md).
    #[arg(long, value_name = "COMMAND", conflicts_with = "connect")]
    runner: Option<String>,
    /// With --runner: the command that cancels a job in its engine when stopped or timed out, with {id}
    /// (as `generate --runner-cancel`).
    #[arg(long, value_name = "COMMAND", requires = "runner")]
    runner_cancel: Option<String>,
    /// Flights at once: embedded mocks (default one per core), --px4 instances or --runner jobs (default 1).
    #[arg(short, long, value_name = "N")]
    jobs: Option<usize>,
    #[command(flatten)]
    px4: Px4Flags,
    /// How the vehicle avoids the boxes.
    #[arg(long, hide = true, value_enum, default_value_t = Mode::Avoidance)]
    mode: Mode,
    /// Judge edition of the distances and points.
    #[arg(long, value_enum, default_value_t = JudgeEdition::E2026)]
    judge: JudgeEdition,
    /// Seed of the mock's gusts (default: the suite's campaign seed, else 0).
    #[arg(long)]
    seed: Option<u64>,
    /// Embedded mock autopilots at once (default: one per core).
    #[arg(long, hide = true, value_name = "N")]
    mock_vehicles: Option<usize>,
    /// Print report.json on stdout.
    #[arg(long)]
    json: bool,
    /// No progress on stderr (warnings and errors still go there).
    #[arg(short, long)]
    quiet: bool,
}

/// The vehicles' settings: the suite's campaign.json when it has one (the same mock it was generated on),
/// else `generate`'s defaults; the flags given here override the backend.
fn config(args: &EvaluateArgs) -> anyhow::Result<CampaignConfig> {
    let stored = args.folder.join("campaign.json");
    // A link or a folder in its place is refused by the reader, naming it, rather than passed over.
    let mut cfg = if std::fs::symlink_metadata(&stored).is_ok() {
        let bytes = read_capped_no_follow(&stored, MAX_READ_BYTES)?;
        serde_json::from_slice::<CampaignConfig>(&bytes)
            .with_context(|| format!("{}: not a campaign", stored.display()))?
    } else {
        defaults(args)
    };
    if args.runner.is_some() {
        cfg.hfs = vec!["runner".into()];
    } else if args.px4.px4.is_some() {
        cfg.hfs = vec!["px4".into()];
    } else if args.connect != "mock" || cfg.hfs != ["mock"] {
        cfg.hfs = args
            .connect
            .split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect();
    }
    cfg.runner = args.runner.clone();
    cfg.px4 = args.px4.backend();
    cfg.judge = args.judge.into();
    cfg.mode = name_of(&args.mode);
    if let Some(seed) = args.seed {
        cfg.seed = seed;
    }
    Ok(cfg)
}

fn defaults(args: &EvaluateArgs) -> CampaignConfig {
    let ask = Ask {
        case: args.folder.clone(),
        budget: 1,
        seed: 0,
        connect: vec!["mock".into()],
        mode: name_of(&args.mode),
        judge: args.judge.into(),
        prior: None,
        runner: None,
        jobs: args.jobs,
        px4: None,
    };
    setup::build(&ask, &Requested::default())
}

fn runner(cfg: &CampaignConfig, args: &EvaluateArgs) -> anyhow::Result<Option<RunnerSettings>> {
    let Some(text) = &cfg.runner else {
        return Ok(None);
    };
    Ok(Some(RunnerSettings {
        template: Template::parse(text).map_err(anyhow::Error::msg)?,
        timeout: std::time::Duration::from_secs_f64(DEFAULT_JOB_TIMEOUT_S),
        judge: cfg.judge,
        spelling: if cfg.old_spelling { Spelling::Old } else { Spelling::New },
        campaign_folder: args.folder.join(prgenuav::campaign::evaluation::flying::EVALUATION_DIR),
        cancel: args
            .runner_cancel
            .as_deref()
            .map(Template::parse_cancel)
            .transpose()
            .map_err(anyhow::Error::msg)?,
    }))
}

/// The numbers given, checked before any vehicle starts.
fn check(args: &EvaluateArgs) -> anyhow::Result<()> {
    limits::EVALUATE_RUNS.check(args.runs as f64)?;
    limits::SIMILAR_BELOW.check(args.similar_below)?;
    if args.top == Some(0) {
        bail!("--top 0 is out of range: 1 or more tests");
    }
    Ok(())
}

/// `--jobs` given to the backend that flies, as `generate` does, within what this machine runs.
fn at_once(cfg: &CampaignConfig, args: &EvaluateArgs) -> anyhow::Result<AtOnce> {
    let at_once = split(cfg, args.jobs, args.mock_vehicles, args.px4.instances)?;
    if let Some(n) = at_once.mock_vehicles {
        let name = if args.mock_vehicles.is_some() {
            "--mock-vehicles"
        } else {
            "--jobs on the embedded mocks"
        };
        if let Some(limit) = find("mock", "vehicles").and_then(|s| s.range) {
            limit.check(name, n as f64).map_err(anyhow::Error::msg)?;
        }
    }
    if let Some(n) = at_once.runner_jobs {
        JOBS.check("--jobs", n as f64).map_err(anyhow::Error::msg)?;
    }
    Ok(at_once)
}

pub fn run(args: EvaluateArgs) -> anyhow::Result<ExitCode> {
    check(&args)?;
    let cfg = config(&args)?;
    if cfg.runner.is_some() && cfg.px4.is_some() {
        bail!("--runner and --px4 are two ways to fly: give one");
    }
    args.px4.check(&cfg)?;
    let at_once = at_once(&cfg, &args)?;
    let plan = Plan {
        runner: runner(&cfg, &args)?,
        cfg,
        folder: args.folder.clone(),
        at_once,
        connect_timeout_s: Flight::default().connect_timeout_s(),
    };
    let (runtime, stop) =
        super::generate::runtime_stopped_by_signals_resuming("run the same evaluate command again to resume")?;
    let mut fleet = vehicles(&plan, &runtime)?;
    let quiet = args.quiet || args.json;
    let on_flight = move |r: &FlightRecord| {
        if !quiet {
            let d = r.flown.min_distance.map_or("-".into(), |d| format!("{d:.2} m"));
            eprintln!(
                "flight candidate {}: {} {d} ({:.0} s)",
                r.candidate, r.flown.status, r.flown.flight_time_s
            );
        }
    };
    let started = Instant::now();
    let on_warning = |w: &str| eprintln!("{w}");
    let setup = EvaluateSetup {
        suite: &args.folder,
        runs: args.runs,
        top: args.top,
        judge: args.judge.into(),
        similar_below_m: args.similar_below,
        cancel: &stop,
        on_flight: &on_flight,
        on_warning: &on_warning,
    };
    let done = evaluate_by_flying(&mut fleet, &setup)?;
    print_summary(&done, args.json, started)?;
    if done.missing.flights > 0 || stop.load(Ordering::SeqCst) {
        eprintln!("incomplete: {} flight(s) missing; why:", done.missing.flights);
        for why in &done.missing.why {
            eprintln!("  - {why}");
        }
        eprintln!("run the same command again to fly them (once what failed is fixed)");
        return Ok(ExitCode::from(super::EXIT_FAIL));
    }
    Ok(ExitCode::SUCCESS)
}

/// report.json on stdout, or the figures in two lines.
fn print_summary(done: &Evaluated, json: bool, started: Instant) -> anyhow::Result<()> {
    let e = &done.evaluation;
    if json {
        println!("{}", report::json(e, &done.missing)?);
        return Ok(());
    }
    println!(
        "final score {:.3} = total {} x sim_pen {:.3} ({} of {} tests similar below DTW {} m); 2025: {} failing, failure score {:.3}",
        e.final_score,
        report::total_with_sd(e),
        e.sim_pen,
        e.similar_tests,
        e.evaluated,
        prgenuav::model::limit::number(e.similar_below_m),
        e.figures_2025.failing,
        e.figures_2025.failure_score
    );
    println!(
        "{} flights this run in {:.0} s; evaluation folder: {}",
        done.outcome.flown,
        started.elapsed().as_secs_f64(),
        done.folder.display()
    );
    Ok(())
}
