//! `prgenuav score FOLDER [--json]`: the competition's metrics for a folder of tests with flights: the
//! 2025 figures (any run below 1.5 m fails, footprint diversity) and the 2026 evaluation (mean points,
//! average trajectories, `sim_pen`, final score).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use prgenuav::campaign::evaluation::Evaluation;
use prgenuav::campaign::evaluation::folder::{evaluate_folder, read_folder};
use prgenuav::campaign::evaluation::folder_score::{SuiteScore, score_flights};
use prgenuav::judge::similarity::SIMILAR_BELOW_M;
use prgenuav::model::limit::number;
use serde::Serialize;

/// Arguments of `score`.
#[derive(Debug, clap::Args)]
pub struct ScoreArgs {
    /// Folder with test_N.yaml files and their flights (test_N.csv, test_N.ulg, or runs test_N-K.csv|ulg).
    folder: PathBuf,
    /// Print the full result as JSON (files named by absolute paths).
    #[arg(long)]
    json: bool,
    /// The judge edition.
    #[command(flatten)]
    judge: super::setting_flags::JudgeFlag,
    /// Two tests are too similar when the DTW distance of their average trajectories is below this (metres,
    /// summed over the alignment; docs/evaluate.md).
    #[arg(long, value_name = "METRES", default_value_t = SIMILAR_BELOW_M)]
    similar_below: f64,
    /// Write each test's average trajectory to DIR/test_N.csv (named in the JSON).
    #[arg(long, value_name = "DIR")]
    averages: Option<PathBuf>,
}

/// The JSON: the 2025 metrics as before, the 2026 evaluation beside them.
#[derive(Serialize)]
struct Both {
    #[serde(flatten)]
    suite: SuiteScore,
    evaluation_2026: Evaluation,
}

pub fn run(mut args: ScoreArgs) -> anyhow::Result<ExitCode> {
    super::limits::SIMILAR_BELOW.check(args.similar_below)?;
    // Absolute, as evaluate's report.json: the JSON's paths resolve from any directory.
    args.folder = absolute(&args.folder)?;
    args.averages = args.averages.as_deref().map(absolute).transpose()?;
    let folder = read_folder(&args.folder)?;
    if folder.no_flights() {
        bail!(
            "{}: none of its {} test(s) has a flight (beside test_N.yaml: test_N.csv, test_N.ulg, or runs \
             test_N-K.csv|ulg): nothing to score",
            args.folder.display(),
            folder.tests.len()
        );
    }
    let suite = score_flights(&folder, args.judge.edition()?)?;
    let evaluation = evaluate_folder(
        &folder,
        args.judge.edition()?,
        args.similar_below,
        args.averages.as_deref(),
    )?;
    for t in evaluation.tests.iter().filter(|t| t.runs.is_empty()) {
        eprintln!("warning: {} has no flight: not evaluated", t.test.display());
    }
    if args.json {
        super::print_json(&Both {
            suite,
            evaluation_2026: evaluation,
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    print_2025(&suite);
    print_2026(&evaluation);
    Ok(ExitCode::SUCCESS)
}

fn absolute(p: &Path) -> anyhow::Result<PathBuf> {
    std::path::absolute(p).with_context(|| format!("{}: cannot resolve the path", p.display()))
}

fn print_2025(suite: &SuiteScore) {
    println!(
        "{:<14} {:>5} {:>10} {:>9} {:>8} {:>7}",
        "test", "runs", "min dist", "time s", "score", "fail"
    );
    for t in &suite.tests {
        let name = t
            .test
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let min = t.runs.iter().map(|r| r.min_distance).fold(f64::INFINITY, f64::min);
        let time = t.runs.iter().map(|r| r.flight_time_s).sum::<f64>() / t.runs.len().max(1) as f64 + 0.0;
        let note = match (t.runs.is_empty(), t.duplicate_of) {
            (true, _) => " (no flight)".to_string(),
            (_, Some(j)) => format!(" (duplicate of test {j})"),
            _ => String::new(),
        };
        let min = if min.is_finite() {
            format!("{min:.3}")
        } else {
            "-".into()
        };
        println!(
            "{name:<14} {:>5} {min:>10} {time:>9.1} {:>8.3} {:>7}{note}",
            t.runs.len(),
            t.score,
            t.failed
        );
    }
    let div = suite.diversity.map_or("n/a".into(), |d| format!("{d:.3}"));
    println!(
        "failing {} / {} evaluated, failure score {:.3}, diversity {div}",
        suite.failing, suite.evaluated, suite.failure_score
    );
    println!("judge {}: {}", suite.judge, suite.judge_definition);
}

fn print_2026(e: &Evaluation) {
    let closest = e.pairs.iter().map(|p| p.dtw).fold(f64::INFINITY, f64::min);
    let closest = if closest.is_finite() {
        format!("closest pair {closest:.1} m")
    } else {
        "no pair to compare: fewer than 2 tests have flights".into()
    };
    // The 2026 protocol (mean points, sim_pen); the distances are the chosen judge's.
    println!(
        "2026 evaluation, judge {}: total score {} x sim_pen {:.3} ({} of {} evaluated tests similar below DTW {} m; {closest}) = final score {:.3}",
        e.judge,
        prgenuav::campaign::evaluation::report::total_with_sd(e),
        e.sim_pen,
        e.similar_tests,
        e.evaluated,
        number(e.similar_below_m),
        e.final_score
    );
    if let Some(note) = prgenuav::campaign::evaluation::report::above_top_note(e) {
        println!("{note}");
    }
}
