//! `prgenuav fidelity DIR [--motion paper|px4] [--json] [--jobs N] [--ensemble N [--seed S]]`: simulated vs real minimum distances.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use prgenuav::lfs::ensemble::{EnsembleParams, MAX_MEMBERS};
use prgenuav::lfs::fidelity::{Aggregates, EnsembleSpec, evaluate_with, load_dir};
use prgenuav::lfs::sim::{MotionModel, SimConfig};

/// Arguments of `fidelity`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folder of flight JSON files (the format of the competition flights in tests/data/hfs-flights).
    dir: PathBuf,
    /// Motion model: paper or px4.
    #[arg(long, default_value = "paper")]
    motion: String,
    /// Print `{"cases": [...], "mae", "spearman", "precision", "recall", "tiers", ...}`.
    #[arg(long)]
    json: bool,
    /// Simulations to run at once (default: 1).
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Also run N perturbed members per case: `p_fail` per case, ROC AUC and Brier score overall and per tier.
    #[arg(long, value_name = "N")]
    ensemble: Option<usize>,
    /// Seed of the ensembles' perturbations.
    #[arg(long, default_value_t = 0, requires = "ensemble")]
    seed: u64,
}

fn opt(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.3}"))
}

fn line(name: &str, a: &Aggregates) -> String {
    let mut s = format!(
        "{name:<8} n {:>3}  MAE {:>6} m  Spearman {:>6}  precision(<1.5) {:>6}  recall(<1.5) {:>6}",
        a.n,
        opt(a.mae),
        opt(a.spearman),
        opt(a.precision),
        opt(a.recall)
    );
    if a.auc.is_some() || a.brier.is_some() {
        s += &format!("  p_fail AUC {:>6}  Brier {:>6}", opt(a.auc), opt(a.brier));
    }
    s
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Some(motion) = MotionModel::by_name(&args.motion) else {
        bail!("unknown motion model {:?} (use paper or px4)", args.motion);
    };
    if args.jobs == 0 {
        bail!("--jobs must be at least 1");
    }
    if let Some(n) = args.ensemble
        && !(1..=MAX_MEMBERS).contains(&n)
    {
        bail!("--ensemble {n}: the number of members must be 1 to {MAX_MEMBERS}");
    }
    let spec = args.ensemble.map(|n| EnsembleSpec {
        params: EnsembleParams::default(),
        n,
        seed: args.seed,
    });
    let (cases, skipped) = load_dir(&args.dir)?;
    if cases.is_empty() {
        bail!(
            "{}: no flight JSON with obstacles and a recorded distance",
            args.dir.display()
        );
    }
    let config = SimConfig {
        motion,
        ..Default::default()
    };
    let report = evaluate_with(&cases, skipped, &config, spec.as_ref(), args.jobs);
    if args.json {
        super::print_json(&report)?;
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "{:<28} {:<5} {:<9} {:>8} {:>9} {:>7} {:>7}  status",
        "case", "tier", "mission", "real", "predicted", "error", "p_fail"
    );
    for c in &report.cases {
        println!(
            "{:<28} {:<5} {:<9} {:>8.3} {:>9} {:>7} {:>7}  {}",
            c.id,
            c.tier,
            c.mission,
            c.real,
            opt(c.predicted),
            opt(c.abs_error),
            opt(c.p_fail),
            c.status.map_or("failed".into(), |s| format!("{s:?}").to_lowercase())
        );
    }
    let overall = Aggregates {
        n: report.cases.iter().filter(|c| c.predicted.is_some()).count(),
        mae: report.mae,
        spearman: report.spearman,
        precision: report.precision,
        recall: report.recall,
        auc: report.auc,
        brier: report.brier,
    };
    println!("{}", line("overall", &overall));
    for (t, a) in &report.tiers {
        println!("{}", line(&format!("tier {t}"), a));
    }
    if let Some(m) = report.hfs_repeat_mae {
        println!("real simulator vs itself (repeated obstacle sets): mean |difference| {m:.3} m");
    }
    if !report.skipped.is_empty() {
        println!(
            "skipped (no obstacles or no recorded distance): {}",
            report.skipped.join(", ")
        );
    }
    Ok(ExitCode::SUCCESS)
}
