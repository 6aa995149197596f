//! `prgenuav simulate TEST.yaml [--motion paper|px4] [--camera NAME] [--json] [--trajectory out.csv] [--plot out.svg]
//! [--ensemble N [--seed S]]`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, bail};
use prgenuav::io::write_atomic;
use prgenuav::judge::{Judge, ObstacleDistance};
use prgenuav::lfs::ensemble::{EnsembleParams, MAX_MEMBERS, run_ensemble};
use prgenuav::lfs::sim::{SimConfig, SimResult, SimStatus, simulate};
use prgenuav::model::TestCase;
use prgenuav::model::competition::FAIL_BELOW_M;
use prgenuav::plot::{FlightPlot, PathStyle};

use super::values::{CameraArg, choice};
use prgenuav::lfs::sim::Motion;

/// Arguments of `simulate`.
#[derive(Debug, clap::Args)]
pub struct SimulateArgs {
    /// The test YAML (obstacles + mission).
    test: PathBuf,
    /// Motion model of the simulated vehicle.
    #[arg(long, value_parser = choice::<Motion>(), default_value = "paper")]
    motion: Motion,
    /// Depth camera preset.
    #[arg(long, value_enum, default_value_t = CameraArg::Hfs)]
    camera: CameraArg,
    /// Print `{"min_distance", "min_distance_raw", "per_obstacle", "status", "flight_time_s", "cycles", "wall_ms"}`, with
    /// `"ensemble": {"n", "seed", "p_fail", "member_min_distances"}` under `--ensemble`.
    #[arg(long)]
    json: bool,
    /// Write the simulated trajectory as an Aerialist CSV (`timestamp,x,y,z,r`).
    #[arg(long, value_name = "FILE.csv")]
    trajectory: Option<PathBuf>,
    /// Write a top-down SVG plot of the flight.
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
    /// The judge edition.
    #[command(flatten)]
    judge: super::setting_flags::JudgeFlag,
    /// Refuse a test that breaks the current competition rules (default: warn and simulate it anyway).
    #[arg(long)]
    strict: bool,
    /// Also fly N perturbed members (tick phase, latency, speed, box jitter) and print `p_fail`, the
    /// probability of a minimum distance below 1.5 m, and the members' spread.
    #[arg(long, value_name = "N")]
    ensemble: Option<usize>,
    /// Seed of the ensemble's perturbations (same seed, same members).
    #[arg(long, default_value_t = 0, requires = "ensemble")]
    seed: u64,
}

#[derive(serde::Serialize)]
struct EnsembleReport {
    n: usize,
    seed: u64,
    p_fail: Option<f64>,
    member_min_distances: Vec<f64>,
}

#[derive(serde::Serialize)]
struct Report {
    judge: Judge,
    judge_definition: &'static str,
    min_distance: Option<f64>,
    min_distance_raw: Option<f64>,
    per_obstacle: Vec<ObstacleDistance>,
    status: SimStatus,
    flight_time_s: f64,
    cycles: u64,
    wall_ms: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    ensemble: Option<EnsembleReport>,
}

pub fn run(args: SimulateArgs) -> anyhow::Result<ExitCode> {
    let judge = args.judge.edition()?;
    super::check_outputs(&[
        ("--trajectory", args.trajectory.as_deref()),
        ("--plot", args.plot.as_deref()),
    ])?;
    let Some(test) = super::load_test(&args.test, args.strict)? else {
        return Ok(ExitCode::from(super::EXIT_FAIL));
    };
    if let Some(n) = args.ensemble
        && !(1..=MAX_MEMBERS).contains(&n)
    {
        bail!("--ensemble {n}: the number of members must be 1 to {MAX_MEMBERS}");
    }
    if args.ensemble.is_some() && test.obstacles.is_empty() {
        bail!(
            "--ensemble: {} has no obstacles, so there is no failure to predict",
            args.test.display()
        );
    }
    let config = SimConfig {
        motion: args.motion.model(),
        camera: args.camera.model(),
        judge,
        ..Default::default()
    };
    let start = Instant::now();
    let result = simulate(&test, &config)?;
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    write_files(&args, &test, &result)?;
    let ensemble = match args.ensemble {
        Some(n) => Some(ensemble(&test, &config, n, args.seed)?),
        None => None,
    };
    let d = result.distance.as_ref();
    let report = Report {
        judge,
        judge_definition: judge.description(),
        min_distance: d.map(|d| d.min_distance),
        min_distance_raw: d.map(|d| d.min_distance_raw),
        per_obstacle: d.map(|d| d.per_obstacle.clone()).unwrap_or_default(),
        status: result.status,
        flight_time_s: result.flight_time_s,
        cycles: result.cycles,
        wall_ms,
        ensemble,
    };
    if args.json {
        super::print_json(&report)?;
    } else {
        print_text(&report, &result, config.motion.name());
    }
    Ok(ExitCode::SUCCESS)
}

/// `--trajectory` and `--plot`.
fn write_files(args: &SimulateArgs, test: &TestCase, result: &SimResult) -> anyhow::Result<()> {
    if let Some(path) = &args.trajectory {
        write_atomic(path, result.trajectory.to_csv().as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &args.plot {
        let mut plot = FlightPlot::new(test);
        plot.add_path(
            &result.trajectory,
            PathStyle::Simulated,
            &format!("simulated ({})", args.motion.model().name()),
        );
        if let Some(d) = &result.distance {
            plot.mark_closest(&d.closest);
        }
        write_atomic(path, plot.to_svg().as_bytes()).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// `--ensemble N`: the members' minimum distances and the failure probability.
fn ensemble(test: &TestCase, config: &SimConfig, n: usize, seed: u64) -> anyhow::Result<EnsembleReport> {
    let params = EnsembleParams::default();
    let jobs = std::thread::available_parallelism().map_or(1, |j| j.get());
    let e = run_ensemble(
        &test.mission,
        &test.obstacles,
        &test.params,
        config,
        &params,
        n,
        seed,
        jobs,
    )?;
    Ok(EnsembleReport {
        n,
        seed,
        p_fail: e.p_fail(&params),
        member_min_distances: e.member_min_distances,
    })
}

fn print_text(report: &Report, result: &SimResult, motion: &str) {
    let judge = report.judge;
    match &result.distance {
        Some(d) => {
            println!(
                "min_distance      {:.3} m (judge {judge}: 0.5 s bins; {})",
                d.min_distance,
                judge.description()
            );
            println!("min_distance_raw  {:.3} m", d.min_distance_raw);
            for o in &d.per_obstacle {
                println!("  obstacle {}: {:.3} m", o.index, o.distance);
            }
        }
        None => println!("min_distance      - (no obstacles)"),
    }
    println!(
        "status            {} after {:.1} s simulated, {} cycles, {:.0} ms wall ({motion} motion model)",
        super::wording::words(&format!("{:?}", result.status)),
        super::wording::non_negative(result.flight_time_s),
        result.cycles,
        report.wall_ms
    );
    if let Some(e) = &report.ensemble {
        let mut v = e.member_min_distances.clone();
        v.sort_by(f64::total_cmp);
        let below = v.iter().filter(|d| **d < FAIL_BELOW_M).count();
        println!(
            "p_fail            {} ({below} of {} members below {FAIL_BELOW_M} m, seed {}; Beta prior)",
            e.p_fail.map_or("-".into(), |p| format!("{p:.3}")),
            e.n,
            e.seed
        );
        if let (Some(lo), Some(hi)) = (v.first(), v.last()) {
            println!(
                "members           min {lo:.3} m, median {:.3} m, max {hi:.3} m",
                median(&v)
            );
        }
    }
}

/// Median of sorted, non-empty values.
fn median(sorted: &[f64]) -> f64 {
    let m = sorted.len() / 2;
    if sorted.len() % 2 == 1 {
        sorted[m]
    } else {
        0.5 * (sorted[m - 1] + sorted[m])
    }
}
