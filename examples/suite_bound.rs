//! Two suites, each evaluated twice the 2026 way (`evaluate --runs 5 --top 10`, then again with another seed
//! on a copy): each suite's score pooled over both evaluations (10 runs a test), their ratio, and the bound
//! "the best 10 of both suites picked by one evaluation's runs and judged on the other's" (both ways, the
//! mean of the two), with each suite's pooled score as a share of it. Pooled and bound scores are before
//! any similarity penalty (the evaluations' own `sim_pen` is printed beside).
//!
//! `cargo run --release --example suite_bound -- A1 A2 B1 B2` (each an evaluated campaign folder, or its
//! `evaluation/report.json`; A = the learning campaign's suite, B = `--no-screen`'s)

#[path = "common/evaluation_report.rs"]
#[allow(dead_code)] // shared with the campaign examples; this one reads report files, not campaign folders
mod evaluation_report;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use evaluation_report::{read_report, tests_by_name};

/// One test's runs in one evaluation: (points, flight time s), and its score per (point per minute).
#[derive(Debug, Clone)]
struct Runs {
    runs: Vec<(f64, f64)>,
    /// score / (mean points / mean flight minutes): 10 / obstacles², the 2026 rules.
    scale: f64,
}

impl Runs {
    fn score(runs: &[(f64, f64)], scale: f64) -> f64 {
        if runs.is_empty() {
            return 0.0;
        }
        let n = runs.len() as f64;
        let points = runs.iter().map(|r| r.0).sum::<f64>() / n;
        let minutes = runs.iter().map(|r| r.1).sum::<f64>() / n / 60.0;
        if minutes > 0.0 { scale * points / minutes } else { 0.0 }
    }
}

/// One evaluation: its tests by file name, and its final score and sim_pen.
struct Evaluation {
    tests: BTreeMap<String, Runs>,
    final_score: f64,
    sim_pen: f64,
}

fn report_path(arg: &str) -> PathBuf {
    let p = Path::new(arg);
    if p.extension().is_some_and(|e| e == "json") {
        p.to_path_buf()
    } else {
        p.join("evaluation/report.json")
    }
}

fn load(arg: &str) -> anyhow::Result<Evaluation> {
    let json = read_report(&report_path(arg))?;
    let mut tests = BTreeMap::new();
    for (name, t) in tests_by_name(&json)? {
        let runs: Vec<(f64, f64)> = t["runs"]
            .as_array()
            .context("runs[]")?
            .iter()
            .filter_map(|r| Some((r["points"].as_f64()?, r["flight_time_s"].as_f64()?)))
            .collect();
        let obstacles = t["obstacles"].as_f64().context("obstacles")?;
        let scale = 10.0 / (obstacles * obstacles);
        tests.insert(name, Runs { runs, scale });
    }
    Ok(Evaluation {
        tests,
        final_score: json["final_score"].as_f64().unwrap_or(f64::NAN),
        sim_pen: json["sim_pen"].as_f64().unwrap_or(f64::NAN),
    })
}

/// Score of `name` in `e` (0 when it was not evaluated there).
fn score_in(e: &Evaluation, name: &str) -> f64 {
    e.tests.get(name).map_or(0.0, |r| Runs::score(&r.runs, r.scale))
}

/// The suite's score over both evaluations' runs pooled, test by test.
fn pooled(a: &Evaluation, b: &Evaluation) -> f64 {
    a.tests
        .iter()
        .map(|(name, r)| {
            let mut runs = r.runs.clone();
            runs.extend(b.tests.get(name).map_or(&[][..], |x| &x.runs[..]));
            Runs::score(&runs, r.scale)
        })
        .sum()
}

/// The best 10 of both suites by evaluation `pick` (0 or 1), judged on the other; (score, tests of suite A).
fn bound(suites: &[[&Evaluation; 2]; 2], pick: usize) -> (f64, usize) {
    let mut all: Vec<(usize, &String)> = (0..2)
        .flat_map(|s| suites[s][pick].tests.keys().map(move |n| (s, n)))
        .collect();
    all.sort_by(|x, y| score_in(suites[y.0][pick], y.1).total_cmp(&score_in(suites[x.0][pick], x.1)));
    let best = &all[..all.len().min(10)];
    let judged = best.iter().map(|(s, n)| score_in(suites[*s][1 - pick], n)).sum();
    (judged, best.iter().filter(|(s, _)| *s == 0).count())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(args.len() == 4, "usage: suite_bound A1 A2 B1 B2");
    let e: Vec<Evaluation> = args.iter().map(|a| load(a)).collect::<anyhow::Result<_>>()?;
    let suites = [[&e[0], &e[1]], [&e[2], &e[3]]];
    let mut pooled_of = [0.0; 2];
    for (i, name) in ["campaign (A)", "--no-screen (B)"].iter().enumerate() {
        let [x, y] = suites[i];
        pooled_of[i] = pooled(x, y);
        println!(
            "{name}: final score {:.3} (sim_pen {:.3}) and {:.3} (sim_pen {:.3}); pooled, 10 runs a test: {:.3}",
            x.final_score, x.sim_pen, y.final_score, y.sim_pen, pooled_of[i]
        );
    }
    println!("pooled ratio A / B: {:.2}", pooled_of[0] / pooled_of[1]);
    let (b1, n1) = bound(&suites, 0);
    let (b2, n2) = bound(&suites, 1);
    let mean = (b1 + b2) / 2.0;
    println!(
        "bound: picked by the first evaluations, judged on the second {b1:.3} ({n1} of A's tests); the other way \
         {b2:.3} ({n2}); mean {mean:.3}"
    );
    for (i, name) in ["A", "B"].iter().enumerate() {
        println!("{name} pooled = {:.0} % of the bound", 100.0 * pooled_of[i] / mean);
    }
    Ok(())
}
