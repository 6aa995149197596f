//! `prgenuav generate CASE.yaml BUDGET [--seed S] [--out DIR] [--hfs mock|URL[,URL...]] [--candidates N]
//! [--threshold M] [--resume FOLDER] [--quiet] [--json]`: the competition's main job.

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::{Context, bail};
use prgenuav::bridge::FlyMode;
use prgenuav::campaign::parallel::available_threads;
use prgenuav::campaign::pool::Vehicle;
use prgenuav::campaign::report::{DISTINCT_IOU, timestamped_folder};
use prgenuav::campaign::run::{CampaignConfig, run_campaign};
use prgenuav::campaign::screen::LfsScreener;
use prgenuav::campaign::vehicles::{LinkVehicle, MockVehicle};
use prgenuav::judge::Judge;
use prgenuav::lfs::ensemble::{EnsembleParams, MAX_MEMBERS};
use prgenuav::lfs::sim::{MotionModel, SimConfig};

use super::progress::Reporter;
use super::sample::GeneratorArgs;

/// Arguments of `generate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The case study YAML (mission, params, commands).
    case: Option<PathBuf>,
    /// High-fidelity flights allowed (the competition's budget).
    budget: Option<usize>,
    /// Seed of the generator: the same seed draws the same candidates.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Where the timestamped output folder is created.
    #[arg(long, default_value = "generated_tests")]
    out: PathBuf,
    /// High-fidelity side: `mock` (embedded mock autopilots, one per core) or MAVLink URLs separated by
    /// commas, one flight per vehicle at a time (e.g. udpin:0.0.0.0:14540,udpin:0.0.0.0:14541).
    #[arg(long, default_value = "mock")]
    hfs: String,
    /// Candidates to draw and screen with the LFS (default: 3 x budget, at least 20).
    #[arg(long)]
    candidates: Option<usize>,
    /// Fly only candidates the LFS predicts closer than this, metres.
    #[arg(long, default_value_t = 3.0)]
    threshold: f64,
    /// Skip a candidate whose footprints overlap an already chosen one by more than this IoU.
    #[arg(long, default_value_t = 0.5)]
    max_iou: f64,
    /// LFS motion model for screening: px4 or paper.
    #[arg(long, default_value = "px4")]
    motion: String,
    /// Obstacle mode of the flights: avoidance (PX4 <= 1.14 companion), offboard, or mission (no avoidance).
    #[arg(long, default_value = "avoidance")]
    mode: String,
    /// Clock speed of the embedded mock autopilots (times real time). In lockstep (the default) it is an
    /// upper bound: the mock holds its clock until each avoidance answer, so flights do not depend on CPU.
    #[arg(long, default_value_t = 100.0)]
    mock_speed: f64,
    /// Let the embedded mocks' clocks run free (no lockstep): flights then depend on how fast the planner
    /// answers, as on a real vehicle; use a low --mock-speed (20) with it.
    #[arg(long)]
    mock_free_running: bool,
    /// In lockstep, the companion plans on the pose this many (vehicle) milliseconds old.
    #[arg(long, default_value_t = prgenuav::campaign::run::DEFAULT_MOCK_LATENCY_MS)]
    mock_latency: f64,
    /// Embedded mock autopilots flying at once (default: one per core). Flights mostly wait on the mock's
    /// clock, so more vehicles than cores can help while the planner keeps up.
    #[arg(long)]
    mock_vehicles: Option<usize>,
    /// Clock rate of the --hfs vehicles (PX4_SIM_SPEED_FACTOR); default: measured on each vehicle as it connects.
    #[arg(long, value_name = "K")]
    hfs_time_scale: Option<f64>,
    /// Give a flight up (LAND) after this many vehicle seconds.
    #[arg(long, default_value_t = 500.0, value_name = "S")]
    timeout: f64,
    /// Seconds to wait for each MAVLink vehicle's first heartbeat.
    #[arg(long, default_value_t = 15.0)]
    connect_timeout: f64,
    /// Skip the LFS: fly candidates in the order drawn (the baseline that shows what screening buys).
    #[arg(long)]
    no_screen: bool,
    /// Members of the LFS ensemble run on the 2 x budget most severe candidates, which are then flown in order
    /// of expected competition points per minute (p_fail x points per failure / predicted minutes); 0 ranks
    /// by the point prediction alone. Default: 8 for MAVLink vehicles, 0 for the embedded mock (an ensemble
    /// costs about 1 s of CPU per candidate, more than a mock flight; a PX4 or hardware flight costs far more).
    #[arg(long, value_name = "N")]
    ensemble: Option<usize>,
    /// Do not learn: screen once, fly the ranking (the static campaign). By default the campaign flies in 8
    /// rounds (up to 12 while near-duplicates leave budget unflown), calibrating the LFS on every flight (a bias,
    /// and a kernel over the flights near each candidate) and adapting the generator towards failures (draws
    /// around the failing flights, and a draw distribution moved towards the best candidates).
    #[arg(long)]
    no_learn: bool,
    /// Learn the LFS's calibration but keep the paper's uniform draws (no draws around the failing flights).
    #[arg(long, conflicts_with = "no_learn")]
    no_adapt: bool,
    /// Start from what an earlier campaign learnt (its output folder's learnt.json).
    #[arg(long, value_name = "FOLDER", conflicts_with = "no_learn")]
    prior: Option<PathBuf>,
    /// Floor of the failing tests' diversity (1 - mean pairwise IoU): the adapted generator draws and flies only
    /// candidates that keep the expected final diversity above it, and backs off below it.
    #[arg(long, default_value_t = 0.8, value_name = "D")]
    min_diversity: f64,
    /// A candidate drawn next to a failing flight may overlap a flown test up to this IoU (more than --max-iou)
    /// as long as the failing tests would keep --min-diversity if it failed too: near copies of a failure fail
    /// most often. Set it to --max-iou to hold every candidate to --max-iou.
    #[arg(long, default_value_t = 0.85, value_name = "IOU")]
    child_max_iou: f64,
    /// Continue a killed campaign in this folder (its campaign.json holds the settings).
    #[arg(long, value_name = "FOLDER")]
    resume: Option<PathBuf>,
    /// No progress output.
    #[arg(long)]
    quiet: bool,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Judge edition of the distances (and of the LFS prediction): 2026 measures from the path buffered by
    /// half the vehicle width, horizontally; 2025 from the bare path with the height-gap rule.
    #[arg(long, default_value = "2026", value_parser = super::parse_judge)]
    judge: Judge,
    /// Re-anchor every test (mission, obstacles, fence) at each vehicle's home (HOME_POSITION) instead of
    /// refusing a vehicle farther from the test's home than its MIS_DIST_1WP (bench drones anywhere).
    #[arg(long)]
    anchor_at_vehicle_home: bool,
    #[command(flatten)]
    generator: GeneratorArgs,
}

fn parse_mode(s: &str) -> anyhow::Result<FlyMode> {
    Ok(match s {
        "avoidance" => FlyMode::Avoidance,
        "offboard" => FlyMode::Offboard,
        "mission" => FlyMode::Mission,
        other => bail!("unknown --mode {other:?} (use avoidance, offboard or mission)"),
    })
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let (cfg, folder) = match &args.resume {
        Some(folder) => {
            let path = folder.join("campaign.json");
            let text = std::fs::read_to_string(&path).with_context(|| format!("{}: cannot read", path.display()))?;
            let cfg: CampaignConfig =
                serde_json::from_str(&text).with_context(|| format!("{}: not a campaign file", path.display()))?;
            (cfg, folder.clone())
        }
        None => {
            let (Some(case), Some(budget)) = (args.case.clone(), args.budget) else {
                bail!("give CASE.yaml and BUDGET, or --resume FOLDER");
            };
            if budget == 0 {
                bail!("BUDGET must be at least 1 flight");
            }
            if !(0.0..=1.0).contains(&args.min_diversity) {
                bail!("--min-diversity must be within 0..1");
            }
            if let Some(p) = &args.prior {
                // Refuse a bad prior before anything is sampled or flown.
                prgenuav::campaign::rounds::load_prior(p)?;
            }
            if !(args.threshold.is_finite()
                && args.threshold > 0.0
                && (0.0..=1.0).contains(&args.max_iou)
                && (0.0..=1.0).contains(&args.child_max_iou))
            {
                bail!("--threshold must be positive, --max-iou and --child-max-iou within 0..1");
            }
            let cfg = CampaignConfig {
                case,
                seed: args.seed,
                budget,
                candidates: args.candidates.unwrap_or((3 * budget).max(20)),
                threshold_m: args.threshold,
                max_iou: args.max_iou,
                generator: args.generator.config()?,
                old_spelling: args.generator.spelling == super::Spelling::Old,
                hfs: args
                    .hfs
                    .split(',')
                    .map(|s| s.trim().to_string())
                    .filter(|s| !s.is_empty())
                    .collect(),
                mode: args.mode.clone(),
                motion: args.motion.clone(),
                mock_speed: args.mock_speed,
                mock_lockstep: !args.mock_free_running,
                mock_latency_ms: args.mock_latency,
                screen: !args.no_screen,
                judge: args.judge,
                anchor_at_vehicle_home: args.anchor_at_vehicle_home,
                hfs_time_scale: args.hfs_time_scale,
                flight_timeout_s: args.timeout,
                ensemble: args.ensemble.unwrap_or(if args.hfs.trim() == "mock" { 0 } else { 8 }),
                learn: !args.no_learn && !args.no_screen,
                adapt: !args.no_learn && !args.no_adapt && !args.no_screen,
                prior: args.prior.clone(),
                min_diversity: args.min_diversity,
                child_max_iou: Some(args.child_max_iou),
            };
            (cfg, timestamped_folder(&args.out, std::time::SystemTime::now()))
        }
    };
    let Some(motion) = MotionModel::by_name(&cfg.motion) else {
        bail!("unknown --motion {:?} (use px4 or paper)", cfg.motion);
    };
    let mode = parse_mode(&cfg.mode)?;
    if !(cfg.mock_speed.is_finite() && cfg.mock_speed >= 1.0) {
        bail!("--mock-speed must be at least 1");
    }
    if cfg.hfs_time_scale.is_some_and(|k| !(k.is_finite() && k > 0.0)) {
        bail!("--hfs-time-scale must be a positive number");
    }
    if !(cfg.flight_timeout_s.is_finite() && cfg.flight_timeout_s > 0.0) {
        bail!("--timeout must be a positive number of seconds");
    }
    if !(cfg.mock_latency_ms.is_finite() && (0.0..=1000.0).contains(&cfg.mock_latency_ms)) {
        bail!("--mock-latency {} must be between 0 and 1000 ms", cfg.mock_latency_ms);
    }
    let lockstep = cfg
        .mock_lockstep
        .then(|| Duration::from_secs_f64(cfg.mock_latency_ms / 1000.0));
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    let stop = Arc::new(AtomicBool::new(false));
    let on_signal = stop.clone();
    runtime.spawn(async move {
        if tokio::signal::ctrl_c().await.is_ok() {
            eprintln!("Ctrl-C: landing the vehicles in flight, keeping every finished flight; resume with --resume");
            on_signal.store(true, Ordering::SeqCst);
        }
    });
    let vehicles: Vec<Box<dyn Vehicle>> = if cfg.hfs == ["mock"] {
        let count = args.mock_vehicles.unwrap_or_else(available_threads);
        if count == 0 {
            bail!("--mock-vehicles must be at least 1");
        }
        (0..count)
            .map(|i| {
                Box::new(
                    MockVehicle::new(runtime.handle().clone(), i, cfg.mock_speed, mode, lockstep)
                        .judged(cfg.judge, cfg.anchor_at_vehicle_home)
                        .with_timeout(cfg.flight_timeout_s),
                ) as Box<dyn Vehicle>
            })
            .collect()
    } else {
        if cfg.hfs.iter().any(|u| u == "mock") {
            bail!("--hfs takes either `mock` or MAVLink URLs, not both");
        }
        cfg.hfs
            .iter()
            .map(|url| {
                Box::new(
                    LinkVehicle::new(
                        runtime.handle().clone(),
                        url,
                        mode,
                        args.connect_timeout,
                        cfg.hfs_time_scale,
                        cfg.flight_timeout_s,
                    )
                    .judged(cfg.judge, cfg.anchor_at_vehicle_home),
                ) as Box<dyn Vehicle>
            })
            .collect()
    };
    if vehicles.is_empty() {
        bail!("--hfs names no vehicle");
    }
    let progress = Reporter::new(args.quiet || args.json);
    if cfg.ensemble > MAX_MEMBERS {
        bail!("--ensemble {}: at most {MAX_MEMBERS} members", cfg.ensemble);
    }
    let screener = LfsScreener {
        config: SimConfig {
            motion,
            judge: cfg.judge,
            ..SimConfig::default()
        },
        ensemble: EnsembleParams::default(),
    };
    let report = run_campaign(&cfg, &folder, &screener, vehicles, &progress, &stop)?;
    if args.json {
        let mut value = serde_json::to_value(&report)?;
        value["output_folder"] = serde_json::json!(folder.display().to_string());
        super::print_json(&value)?;
    } else {
        let s = &report.suite;
        let three = if s.failing_with_three > 0 {
            format!(", {} with three obstacles", s.failing_with_three)
        } else {
            String::new()
        };
        println!(
            "{} failing tests ({} distinct at IoU {DISTINCT_IOU}{three}) of {} flights ({} candidates screened), \
             failure score {:.2}, diversity {}",
            s.failing,
            s.distinct_failing,
            s.flown,
            s.candidates_screened,
            s.failure_score,
            s.diversity.map_or("n/a".into(), |d| format!("{d:.3}"))
        );
        println!("output folder: {}", folder.display());
    }
    if let Some(w) = floor_warning(report.suite.diversity, cfg.adapt, cfg.min_diversity) {
        eprintln!("warning: {w}");
    }
    if stop.load(Ordering::SeqCst) {
        eprintln!(
            "interrupted: resume with  prgenuav generate --resume {}",
            folder.display()
        );
        return Ok(ExitCode::from(super::EXIT_FAIL));
    }
    Ok(ExitCode::SUCCESS)
}

/// The floor bounds an expectation: what to say when a learning campaign's failing tests still ended below it.
fn floor_warning(diversity: Option<f64>, adapt: bool, floor: f64) -> Option<String> {
    let d = diversity.filter(|&d| adapt && d < floor)?;
    Some(format!(
        "the failing tests' diversity {d:.3} ended below --min-diversity {floor} (the campaign kept their expected \
         diversity above it; the failures fell closer together than expected)"
    ))
}

#[cfg(test)]
mod tests {
    use super::floor_warning;

    #[test]
    fn a_learning_campaign_below_its_diversity_floor_says_so() {
        let w = floor_warning(Some(0.708), true, 0.8).unwrap();
        assert!(w.contains("0.708") && w.contains("--min-diversity 0.8"), "{w}");
        assert_eq!(floor_warning(Some(0.81), true, 0.8), None);
        assert_eq!(floor_warning(None, true, 0.8), None, "fewer than two failing tests");
        assert_eq!(
            floor_warning(Some(0.5), false, 0.8),
            None,
            "static campaigns have no floor"
        );
    }
}
