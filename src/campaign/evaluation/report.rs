//! The evaluation's `report.json` (the [`Evaluation`] with the flights still missing) and `report.md`.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use super::missing::Missing;
use super::suite::Evaluation;
use crate::judge::above_top_count;
use crate::model::ModelError;
use crate::model::limit::number;

/// `report.json`.
#[derive(Serialize)]
struct ReportJson<'a> {
    /// Flights not yet made (0 when the evaluation is complete).
    missing_flights: usize,
    /// Why they are missing, one line each.
    missing_why: &'a [String],
    #[serde(flatten)]
    evaluation: &'a Evaluation,
}

/// The JSON text of the report.
pub fn json(evaluation: &Evaluation, missing: &Missing) -> Result<String, ModelError> {
    serde_json::to_string_pretty(&ReportJson {
        missing_flights: missing.flights,
        missing_why: &missing.why,
        evaluation,
    })
    .map_err(|e| ModelError::Syntax {
        path: "report.json".into(),
        line: None,
        column: None,
        message: format!("cannot be written as JSON: {e}"),
    })
}

/// Writes `report.json` and `report.md` into `folder` (each atomically).
pub fn write(folder: &Path, evaluation: &Evaluation, missing: &Missing) -> Result<(), ModelError> {
    crate::io::write_atomic(&folder.join("report.json"), json(evaluation, missing)?.as_bytes())?;
    crate::io::write_atomic(&folder.join("report.md"), markdown(evaluation, missing).as_bytes())
}

/// The total score with its standard error from the runs, where there is one.
pub fn total_with_sd(e: &Evaluation) -> String {
    match e.total_score_sd {
        Some(sd) => format!("{:.3} (sd {sd:.3} from the runs' own scatter)", e.total_score),
        None => format!("{:.3}", e.total_score),
    }
}

fn name(p: &Path) -> String {
    p.file_name()
        .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// The report for people: the figures, the tests, the closest pairs.
pub fn markdown(e: &Evaluation, missing: &Missing) -> String {
    let mut md = String::from("# 2026 evaluation\n\n");
    if missing.flights > 0 {
        let _ = writeln!(md, "**Incomplete: {} flight(s) missing.** Why:\n", missing.flights);
        for why in &missing.why {
            let _ = writeln!(md, "- {why}");
        }
        let _ = writeln!(
            md,
            "\nRun the same `evaluate` command again to fly them (once what failed is fixed).\n"
        );
    }
    let _ = writeln!(
        md,
        "| figure | value |\n|---|---|\n| final score | {:.3} |\n| total score | {} |\n| sim_pen | {:.3} ({} of {} evaluated tests similar) |\n| similar below | DTW {} m |\n| 2025: failing tests | {} |\n| 2025: failure score | {:.3} |\n| 2025: diversity | {} |\n",
        e.final_score,
        total_with_sd(e),
        e.sim_pen,
        e.similar_tests,
        e.evaluated,
        number(e.similar_below_m),
        e.figures_2025.failing,
        e.figures_2025.failure_score,
        e.figures_2025.diversity.map_or("n/a".into(), |d| format!("{d:.3}")),
    );
    let _ = writeln!(md, "Judge {}: {}\n", e.judge, e.judge_definition);
    above_top(&mut md, e);
    md.push_str("| test | runs: distance m (points) | mean points | mean time s | score | similar to |\n|---|---|---|---|---|---|\n");
    for t in &e.tests {
        let runs: Vec<String> = t
            .runs
            .iter()
            .map(|r| match r.above_top {
                Some(o) => format!("{:.2} ({}, above obstacle {})", r.min_distance, r.points, o.obstacle),
                None => format!("{:.2} ({})", r.min_distance, r.points),
            })
            .collect();
        let runs = if runs.is_empty() {
            vec!["no flight judged".to_string()]
        } else {
            runs
        };
        let similar = t.similar_to.map_or(String::new(), |j| name(&e.tests[j].test));
        let _ = writeln!(
            md,
            "| {} | {} | {:.2} | {:.1} | {:.3} | {similar} |",
            name(&t.test),
            runs.join(", "),
            t.mean_points,
            t.mean_flight_time_s,
            t.score
        );
    }
    closest_pairs(&mut md, e);
    md
}

fn closest_pairs(md: &mut String, e: &Evaluation) {
    if e.pairs.is_empty() {
        let _ = writeln!(
            md,
            "\nNo pair of average trajectories to compare: {} test(s) with flights (the similarity penalty needs two).",
            e.evaluated
        );
        return;
    }
    let mut pairs: Vec<_> = e.pairs.iter().collect();
    pairs.sort_by(|a, b| a.dtw.total_cmp(&b.dtw));
    md.push_str(
        "\nClosest pairs of average trajectories (DTW, metres):\n\n| a | b | DTW | similar |\n|---|---|---|---|\n",
    );
    for p in pairs.iter().take(10) {
        let _ = writeln!(md, "| {} | {} | {:.1} | {} |", name(&p.a), name(&p.b), p.dtw, p.similar);
    }
}

/// Says how many runs were above a box's top where they came closest to it, and how the judge scored them
/// (`None` when none were).
pub fn above_top_note(e: &Evaluation) -> Option<String> {
    let (runs, lowest) = above_top_count(e.tests.iter().flat_map(|t| &t.runs).map(|r| r.above_top))?;
    Some(format!(
        "{runs} run(s) came closest to a box above its top (the lowest {lowest:.2} m above): {}.",
        e.judge.above_top_rule()
    ))
}

fn above_top(md: &mut String, e: &Evaluation) {
    if let Some(note) = above_top_note(e) {
        let _ = writeln!(
            md,
            "**{note}** Such runs are marked \"above obstacle K\" (K as in `report.json`, from 0).\n"
        );
    }
}
