//! `prgenuav distance TEST.yaml FLIGHT.csv [--json]`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use prgenuav::judge::judge_flight;

use prgenuav::model::{TestCase, Trajectory};

/// Arguments of `distance`.
#[derive(Debug, clap::Args)]
pub struct DistanceArgs {
    /// The test YAML (its obstacles are measured against).
    test: PathBuf,
    /// The flight: an Aerialist trajectory CSV (`timestamp,x,y,z,r`, microseconds, local NED, z up).
    flight: PathBuf,
    /// Print `{"judge", "min_distance", "min_distance_raw", "per_obstacle", ...}`.
    #[arg(long)]
    json: bool,
    /// The judge edition.
    #[command(flatten)]
    judge: super::setting_flags::JudgeFlag,
}

pub fn run(args: DistanceArgs) -> anyhow::Result<ExitCode> {
    let judge = args.judge.edition()?;
    let test = TestCase::load(&args.test)?;
    let flight = Trajectory::load_csv(&args.flight)?;
    let Some(verdict) = judge_flight(&flight, &test.obstacles, judge) else {
        bail!("{}: the test has no obstacles to measure against", args.test.display());
    };
    if args.json {
        super::print_json(&verdict)?;
    } else {
        println!(
            "min_distance      {:.3} m (judge {}: origin-aligned, 0.5 s bins; {})",
            verdict.min_distance,
            judge,
            judge.description()
        );
        println!("min_distance_raw  {:.3} m (every sample)", verdict.min_distance_raw);
        for d in &verdict.per_obstacle {
            println!(
                "  obstacle {}: {:.3} m (raw {:.3} m)",
                d.index, d.distance, d.distance_raw
            );
        }
        let c = verdict.closest;
        println!(
            "closest approach  t = {:.2} s at x = {:.2}, y = {:.2}, z = {:.2} (obstacle {})",
            c.t_s, c.x, c.y, c.z, c.obstacle
        );
        if verdict.collision {
            println!("collision: the path entered a box");
        }
        if let Some(o) = verdict.above_top {
            println!(
                "above the top     of obstacle {} by {:.2} m at the closest approach (the distance is horizontal)",
                o.obstacle, o.height_m
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
