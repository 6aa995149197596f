//! `prgenuav simulate TEST.yaml [--motion paper|px4] [--camera NAME] [--json] [--trajectory out.csv] [--plot out.svg]`.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, bail};
use prgenuav::io::write_atomic;
use prgenuav::judge::{Judge, ObstacleDistance};
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
    /// Print `{"min_distance", "min_distance_raw", "per_obstacle", "status", "flight_time_s", "cycles", "wall_ms"}`.
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
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Some(motion) = MotionModel::by_name(&args.motion) else {
        bail!("unknown motion model {:?} (use paper or px4)", args.motion);
    };
    let camera = super::camera_preset(&args.camera)?;
    let Some(test) = super::load_test(&args.test, args.strict)? else {
        return Ok(ExitCode::from(super::EXIT_FAIL));
    };
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
    }
    Ok(ExitCode::SUCCESS)
}
