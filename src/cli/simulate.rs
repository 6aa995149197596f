//! `prgenuav simulate TEST.yaml [--motion paper|px4] [--camera NAME] [--json] [--trajectory out.csv] [--plot out.svg]
//! [--ensemble N [--seed S]]`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, bail};
use prgenuav::io::write_atomic;
use prgenuav::judge::{Judge, ObstacleDistance};
use prgenuav::lfs::ensemble::{EnsembleParams, MAX_MEMBERS, run_ensemble};
use prgenuav::lfs::fidelity::FAIL_BELOW_M;
use prgenuav::lfs::sim::{MotionModel, SimConfig, Status, simulate};
use prgenuav::plot::{FlightPlot, PathStyle};

/// Arguments of `simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The test YAML (obstacles + mission).
    test: PathBuf,
    /// Motion model: `paper` (the paper's kinematic rule) or `px4` (waypoint generator + PX4-like tracking).
    #[arg(long, default_value = "paper")]
    motion: String,
    /// Depth camera preset: hfs (default), 2019, d455.
    #[arg(long, default_value = "hfs")]
    camera: String,
    /// Print `{"min_distance", "min_distance_raw", "per_obstacle", "status", "flight_time_s", "cycles", "wall_ms"}`, with
    /// `"ensemble": {"n", "seed", "p_fail", "member_min_distances"}` under `--ensemble`.
    #[arg(long)]
    json: bool,
    /// Write the simulated trajectory as an Aerialist CSV (`timestamp,x,y,z,r`).
    #[arg(long)]
    trajectory: Option<PathBuf>,
    /// Write a top-down SVG plot of the flight.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Judge edition of the predicted distance: 2026 (path buffered by half the vehicle width, horizontal) or
    /// 2025 (bare path, height-gap rule).
    #[arg(long, default_value = "2026", value_parser = super::parse_judge)]
    judge: Judge,
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
    status: Status,
    flight_time_s: f64,
    cycles: u64,
    wall_ms: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    ensemble: Option<EnsembleReport>,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Some(motion) = MotionModel::by_name(&args.motion) else {
        bail!("unknown motion model {:?} (use paper or px4)", args.motion);
    };
    let camera = super::camera_preset(&args.camera)?;
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
        motion,
        camera,
        judge: args.judge,
        ..Default::default()
    };
    let start = Instant::now();
    let result = simulate(&test, &config)?;
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    if let Some(path) = &args.trajectory {
        write_atomic(path, result.trajectory.to_csv().as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
    }
    if let Some(path) = &args.plot {
        let mut plot = FlightPlot::new(&test);
        plot.add_path(
            &result.trajectory,
            PathStyle::Simulated,
            &format!("simulated ({})", motion.name()),
        );
        if let Some(d) = &result.distance {
            plot.mark_closest(&d.closest);
        }
        write_atomic(path, plot.to_svg().as_bytes()).with_context(|| format!("writing {}", path.display()))?;
    }
    let ensemble = match args.ensemble {
        Some(n) => {
            let params = EnsembleParams::default();
            let jobs = std::thread::available_parallelism().map_or(1, |j| j.get());
            let e = run_ensemble(
                &test.mission,
                &test.obstacles,
                &test.params,
                &config,
                &params,
                n,
                args.seed,
                jobs,
            )?;
            Some(EnsembleReport {
                n,
                seed: args.seed,
                p_fail: e.p_fail(&params),
                member_min_distances: e.member_min_distances,
            })
        }
        None => None,
    };
    let d = result.distance.as_ref();
    let report = Report {
        judge: args.judge,
        judge_definition: args.judge.description(),
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
        match d {
            Some(d) => println!(
                "min_distance      {:.3} m (judge {}: 0.5 s bins; {})",
                d.min_distance,
                args.judge,
                args.judge.description()
            ),
            None => println!("min_distance      - (no obstacles)"),
        }
        if let Some(d) = d {
            println!("min_distance_raw  {:.3} m", d.min_distance_raw);
            for o in &d.per_obstacle {
                println!("  obstacle {}: {:.3} m", o.index, o.distance);
            }
        }
        println!(
            "status            {:?} after {:.1} s simulated, {} cycles, {:.0} ms wall ({} motion)",
            result.status,
            result.flight_time_s,
            result.cycles,
            wall_ms,
            motion.name()
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
            println!(
                "members           min {:.3} m, median {:.3} m, max {:.3} m",
                v[0],
                median(&v),
                v[v.len() - 1]
            );
        }
    }
    Ok(ExitCode::SUCCESS)
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
