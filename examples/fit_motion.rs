//! Grid search of the motion models' free constants against the competition's recorded flights.
//!
//! `cargo run --release --example fit_motion -- paper|paper-delay|px4|px4-low-gain [JOBS]` simulates every
//! usable flight of `tests/data/hfs-flights` for each grid point and prints MAE, Spearman and precision/recall of
//! "below 1.5 m" (overall, per tier and per fixed half of the flights, for fit-on-one-half numbers). Not a
//! test: it takes minutes. The chosen values and the numbers are documented in docs/design-constants.md.

use std::path::Path;

use prgenuav::lfs::fidelity::{FidelityReport, FlightCase, aggregate_half, evaluate, load_dir};
use prgenuav::lfs::motion::{PaperParams, Px4Params};
use prgenuav::lfs::sim::{MotionModel, SimConfig};

fn show(label: &str, r: &FidelityReport, cases: &[FlightCase]) {
    let f = |v: Option<f64>| v.map_or("  -  ".into(), |v| format!("{v:.3}"));
    let tiers: Vec<String> = r
        .tiers
        .iter()
        .map(|(t, a)| format!("{t}: mae {} rho {}", f(a.mae), f(a.spearman)))
        .chain((0..2).map(|h| {
            let a = aggregate_half(r, cases, h);
            format!("half{h}: mae {} rho {}", f(a.mae), f(a.spearman))
        }))
        .collect();
    println!(
        "{label:<44} MAE {} rho {} P {} R {} | {}",
        f(r.mae),
        f(r.spearman),
        f(r.precision),
        f(r.recall),
        tiers.join(" | ")
    );
}

fn main() {
    let mut args = std::env::args().skip(1);
    let model = args.next().unwrap_or_else(|| "paper".into());
    let jobs: usize = args.next().and_then(|j| j.parse().ok()).unwrap_or(2);
    let (cases, skipped) = match load_dir(Path::new("tests/data/hfs-flights")) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let mut grid: Vec<(String, MotionModel)> = Vec::new();
    match model.as_str() {
        "paper" => {
            for speed in [2.0, 3.0] {
                for yaw in [13.5, 30.0] {
                    for frac in [1.0 / 3.0, 1.0] {
                        let p = PaperParams {
                            max_speed_m_s: speed,
                            max_yaw_rate_deg_s: yaw,
                            full_speed_yaw_fraction: frac,
                            delay_ticks: 0,
                        };
                        grid.push((format!("speed {speed} yaw {yaw} frac {frac:.2}"), MotionModel::Paper(p)));
                    }
                }
            }
        }
        "paper-delay" => {
            for delay_ticks in 0..=4 {
                let p = PaperParams {
                    delay_ticks,
                    ..PaperParams::default()
                };
                grid.push((format!("delay {delay_ticks}"), MotionModel::Paper(p)));
            }
        }
        "px4" | "px4-low-gain" => {
            let (gains, speeds, yaws): (&[f64], &[f64], &[f64]) = if model == "px4" {
                (&[0.5, 0.95], &[3.0, 5.0], &[30.0, 45.0])
            } else {
                (&[0.2, 0.3], &[5.0], &[45.0, 90.0])
            };
            for &gain in gains {
                for &speed in speeds {
                    for &yaw in yaws {
                        let p = Px4Params {
                            pos_gain_per_s: gain,
                            max_speed_xy_m_s: speed,
                            max_yaw_rate_deg_s: yaw,
                            ..Px4Params::default()
                        };
                        grid.push((format!("gain {gain} speed {speed} yaw {yaw}"), MotionModel::Px4(p)));
                    }
                }
            }
        }
        other => {
            eprintln!("error: unknown model {other:?} (paper, paper-delay, px4 or px4-low-gain)");
            std::process::exit(2);
        }
    }
    for (label, motion) in grid {
        let config = SimConfig {
            motion,
            ..Default::default()
        };
        let report = evaluate(&cases, skipped.clone(), &config, jobs);
        show(&label, &report, &cases);
    }
}
