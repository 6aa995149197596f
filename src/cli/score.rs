//! `prgenuav score FOLDER [--json]`: the competition's metrics for a folder of tests with flights.

use std::path::PathBuf;
use std::process::ExitCode;

use super::values::JudgeEdition;
use anyhow::bail;
use prgenuav::campaign::report::folder_score::score_folder;

/// Arguments of `score`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folder with test_N.yaml files and their flights (test_N.csv, test_N.ulg, or runs test_N-K.csv|ulg).
    folder: PathBuf,
    /// Print the full result as JSON.
    #[arg(long)]
    json: bool,
    /// Judge edition of the distances and points.
    #[arg(long, value_enum, default_value_t = JudgeEdition::E2026)]
    judge: JudgeEdition,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let suite = score_folder(&args.folder, args.judge.into())?;
    if suite.tests.is_empty() {
        bail!("{}: no test_N.yaml files", args.folder.display());
    }
    if args.json {
        super::print_json(&suite)?;
        return Ok(ExitCode::SUCCESS);
    }
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
        let time = t.runs.iter().map(|r| r.flight_time_s).sum::<f64>() / t.runs.len().max(1) as f64;
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
    Ok(ExitCode::SUCCESS)
}
