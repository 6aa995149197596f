//! `prgenuav fidelity DIR [--motion paper|px4] [--json] [--jobs N] [--ensemble N [--seed S]] [--cv K [--cv-seed S]]
//! [--fov-estimate fixed|maxima]`:
//! simulated vs real minimum distances; with `--ensemble`, a failure probability per case (AUC, Brier); with
//! `--cv`, the cross-validated figure of the fitted constants beside the in-sample one.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::bail;
use prgenuav::lfs::cv::{CvReport, Truth, assign_folds, cross_validate, default_grid, obstacle_sets, predict_grid};
use prgenuav::lfs::ensemble::{EnsembleParams, MAX_MEMBERS};
use prgenuav::lfs::fidelity::{Aggregates, EnsembleSpec, FidelityReport, FlightCase, evaluate_with, load_dir};
use prgenuav::lfs::sim::SimConfig;

use super::values::{FovEstimateArg, choice};
use prgenuav::campaign::settings::Choice;
use prgenuav::lfs::sim::Motion;

/// Arguments of `fidelity`.
#[derive(Debug, clap::Args)]
pub struct FidelityArgs {
    /// Folder of flight JSON files (the format of the competition flights in tests/data/hfs-flights).
    dir: PathBuf,
    /// Motion model of the simulated vehicle.
    #[arg(long, value_parser = choice::<Motion>(), default_value = "paper")]
    motion: Motion,
    /// Print `{"cases": [...], "mae", "spearman", "precision", "recall", "tiers", ...}`.
    #[arg(long)]
    json: bool,
    /// Simulations to run at once (default: 1).
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Cross-validate the motion model's fitted constants with K folds by obstacle set (and leave one tier
    /// out): simulates every flight once per grid point (12 for paper, 6 for px4; minutes). The ensemble's
    /// scales are cross-validated by `examples/fit_ensemble.rs`.
    #[arg(long, value_name = "K", conflicts_with = "ensemble")]
    cv: Option<usize>,
    /// Seed of the fold assignment.
    #[arg(long, default_value_t = 0, requires = "cv")]
    cv_seed: u64,
    /// Also run N perturbed members per case: `p_fail` per case, ROC AUC and Brier score overall and per tier.
    #[arg(long, value_name = "N")]
    ensemble: Option<usize>,
    /// Seed of the ensembles' perturbations.
    #[arg(long, default_value_t = 0, requires = "ensemble")]
    seed: u64,
    /// Where the planner's camera FOV comes from (default: the planner's default).
    #[arg(long, value_enum)]
    fov_estimate: Option<FovEstimateArg>,
}

fn opt(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.3}"))
}

fn line(name: &str, a: &Aggregates) -> String {
    let mut s = format!(
        "{name:<20} n {:>3}  MAE {:>6} m  Spearman {:>6}  precision(<1.5) {:>6}  recall(<1.5) {:>6}",
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

pub fn run(args: FidelityArgs) -> anyhow::Result<ExitCode> {
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
    let mut base = SimConfig::default();
    if let Some(e) = args.fov_estimate {
        base.planner.fov_estimate = e.into();
    }
    let (cases, skipped) = load_dir(&args.dir)?;
    if cases.is_empty() {
        bail!(
            "{}: no flight JSON with obstacles and a recorded distance",
            args.dir.display()
        );
    }
    if let Some(k) = args.cv {
        return run_cv(&args, &cases, &base, k);
    }
    let config = SimConfig {
        motion: args.motion.model(),
        ..base
    };
    let report = evaluate_with(&cases, skipped, &config, spec.as_ref(), args.jobs);
    if args.json {
        super::print_json(&report)?;
    } else {
        print_report(&report);
    }
    Ok(ExitCode::SUCCESS)
}

fn print_report(report: &FidelityReport) {
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
}

fn run_cv(args: &FidelityArgs, cases: &[FlightCase], base: &SimConfig, k: usize) -> anyhow::Result<ExitCode> {
    let motion = args.motion.name().to_string();
    let Some(grid) = default_grid(&motion) else {
        bail!("no cross-validation grid for motion model {motion}");
    };
    let sets = obstacle_sets(cases);
    let Some(folds) = assign_folds(cases, k, args.cv_seed) else {
        bail!(
            "--cv {k}: needs at least 2 folds and no more folds than obstacle sets ({sets} in {})",
            args.dir.display()
        );
    };
    eprintln!(
        "cross-validating {} grid points x {} flights ({} obstacle sets, {k} folds)...",
        grid.len(),
        cases.len(),
        sets
    );
    let preds = predict_grid(cases, &grid, base, args.jobs);
    let truth = Truth::of(cases);
    let Some(report) = cross_validate(&grid, &preds, &truth, &folds, k, args.cv_seed, sets) else {
        bail!("no grid point predicted the training flights of every fold (every simulation failed?)");
    };
    if args.json {
        super::print_json(&report)?;
    } else {
        print_cv(&report);
    }
    Ok(ExitCode::SUCCESS)
}

fn print_cv(r: &CvReport) {
    println!(
        "{}-fold cross-validation by obstacle set ({} sets, seed {}), choosing the {}:",
        r.k, r.obstacle_sets, r.seed, r.criterion
    );
    println!("{}", line("cross-validated", &r.cross_validated));
    for (t, a) in &r.cross_validated_tiers {
        println!("{}", line(&format!("  cv tier {t}"), a));
    }
    println!("{}", line("in-sample", &r.in_sample));
    for (t, a) in &r.in_sample_tiers {
        println!("{}", line(&format!("  in-sample tier {t}"), a));
    }
    println!("in-sample choice: {}", r.in_sample_chosen);
    for f in r.folds.iter().chain(&r.leave_one_tier_out) {
        println!(
            "{:<8} (n {:>3}) chose {:<48} held out: MAE {} m, Spearman {}",
            f.held_out,
            f.n_held_out,
            f.chosen,
            opt(f.held_out_figure.mae),
            opt(f.held_out_figure.spearman)
        );
    }
    println!("grid (in-sample):");
    for (label, a) in &r.grid {
        println!("  {}", line(label, a));
    }
}
