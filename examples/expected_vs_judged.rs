//! How well a campaign's figures foretell the judge: for every written test of campaign folders that were
//! evaluated (`evaluate CAMPAIGN --runs 5`), its expected points, its own campaign flights and its evaluation
//! flights. Prints each folder's sums and the median gap between a test's evaluation and campaign distances;
//! then, over all tests, how the campaign's figures rank the judged means (Spearman), how far the expected
//! points lie from them, and how much a test's evaluation flights scatter.
//!
//! ```sh
//! cargo run --profile test --example expected_vs_judged -- CAMPAIGN...
//! JUDGED=tests/data/px4-repeated/tests.jsonl,OTHER/evaluation/report.json \
//!     cargo run --profile test --example expected_vs_judged -- CAMPAIGN...
//! ```
//!
//! Tests are matched to their evaluation by their boxes, so a campaign re-reported on a copy (`generate
//! --resume`, its tests renamed) is judged by the flights of the original's evaluation. `JUDGED` adds
//! judged flights from elsewhere: `evaluate`'s `report.json` files, or `tests.jsonl` lines with `obstacles`
//! and `px4_min_distance`; the first source that has a test wins, then the folder's own evaluation.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use prgenuav::campaign::store::journal::Journal;
use prgenuav::judge::points;
use prgenuav::lfs::fidelity::spearman;
use prgenuav::model::{Obstacle, TestCase};

// The shared module's `evaluated_tests` matches by file name, for the other examples; this one matches by boxes.
#[allow(dead_code)]
#[path = "common/evaluation_report.rs"]
mod evaluation_report;
use evaluation_report::campaign_folders;

/// One written, evaluated test.
struct Row {
    /// Expected points per flight (`None` from a campaign that had none).
    expected: Option<f64>,
    /// Whether the judged mean fell inside the campaign's 10-90 % interval of the judge's 5-flight mean.
    held: Option<bool>,
    /// Its campaign flights' distances, metres.
    own: Vec<f64>,
    /// Judged mean points.
    judged: f64,
    /// Its evaluation flights' distances, metres.
    runs: Vec<f64>,
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}

fn points_of(v: &[f64]) -> f64 {
    mean(&v.iter().map(|&d| f64::from(points(d))).collect::<Vec<_>>())
}

/// Judged flights' distances by the test's boxes (their JSON).
type Judged = HashMap<String, Vec<f64>>;

/// The numbers of a JSON array: each element itself, or its `field`.
fn distances(runs: &serde_json::Value, field: Option<&str>) -> Vec<f64> {
    let runs = runs.as_array().map(Vec::as_slice).unwrap_or_default();
    let value = |r: &serde_json::Value| field.map_or(r.as_f64(), |f| r[f].as_f64());
    runs.iter().filter_map(value).collect()
}

/// The canonical key of a test's boxes (as a test YAML or report.json spells them).
fn boxes_key(obstacles: &serde_json::Value) -> Option<String> {
    let boxes: Vec<Obstacle> = serde_json::from_value(obstacles.clone()).ok()?;
    serde_json::to_string(&boxes).ok()
}

/// The boxes of an evaluated test's YAML: its path as written, else under a folder above the report (reports
/// of older versions name it relative to where `evaluate` ran).
fn test_boxes(test: &str, report: &Path) -> Option<String> {
    let found = std::iter::once(PathBuf::from(test))
        .chain(report.ancestors().map(|a| a.join(test)))
        .find(|p| p.is_file())?;
    let case = TestCase::load(&found).ok()?;
    serde_json::to_string(&case.obstacles).ok()
}

/// Adds the evaluated tests of the `evaluate` report at `path` to `into`.
fn add_report(path: &Path, into: &mut Judged) -> anyhow::Result<()> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text).with_context(|| path.display().to_string())?;
    for t in json["tests"].as_array().map(Vec::as_slice).unwrap_or_default() {
        let runs = distances(&t["runs"], Some("min_distance"));
        if let (Some(key), false) = (
            test_boxes(t["test"].as_str().unwrap_or_default(), path),
            runs.is_empty(),
        ) {
            into.entry(key).or_insert(runs);
        }
    }
    Ok(())
}

/// The judged flights of the `JUDGED` sources, then of `folder`'s own evaluation.
fn judged(folder: &Path, extra: &Judged) -> anyhow::Result<Judged> {
    let mut out = extra.clone();
    let own = folder.join("evaluation/report.json");
    if own.is_file() {
        add_report(&own, &mut out)?;
    }
    Ok(out)
}

/// The flights named by the env `JUDGED` (comma-separated files).
fn extra_judged() -> anyhow::Result<Judged> {
    let mut out = Judged::new();
    let Ok(list) = std::env::var("JUDGED") else {
        return Ok(out);
    };
    for path in list.split(',').filter(|p| !p.is_empty()) {
        if !path.ends_with(".jsonl") {
            add_report(Path::new(path), &mut out)?;
            continue;
        }
        let text = std::fs::read_to_string(path).with_context(|| format!("JUDGED: reading {path}"))?;
        for (i, line) in text.lines().enumerate() {
            let row: serde_json::Value = serde_json::from_str(line).with_context(|| format!("{path}:{}", i + 1))?;
            let key = boxes_key(&row["obstacles"]).with_context(|| format!("{path}:{}: obstacles", i + 1))?;
            out.entry(key).or_insert(distances(&row["px4_min_distance"], None));
        }
    }
    Ok(out)
}

/// Each candidate's charged campaign flights' distances.
fn own_flights(folder: &Path) -> anyhow::Result<HashMap<u64, Vec<f64>>> {
    let path = folder.join("journal.jsonl");
    let records = Journal::read(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut out: HashMap<u64, Vec<f64>> = HashMap::new();
    for r in &records {
        if let Some(d) = r.flown.min_distance {
            out.entry(r.candidate.0).or_default().push(d);
        }
    }
    Ok(out)
}

fn rows_of(folder: &Path, extra: &Judged) -> anyhow::Result<Vec<Row>> {
    let text = std::fs::read_to_string(folder.join("report.json"))?;
    let json: serde_json::Value = serde_json::from_str(&text)?;
    let (judged, own) = (judged(folder, extra)?, own_flights(folder)?);
    let mut out = Vec::new();
    for t in json["tests"].as_array().context("report.json: no tests[]")? {
        let written = t["reported_as"].as_str().is_some_and(|n| n.starts_with("test_"));
        let own = t["candidate"].as_u64().and_then(|c| own.get(&c).cloned());
        let runs = boxes_key(&t["obstacles"])
            .and_then(|k| judged.get(&k))
            .filter(|_| written)
            .cloned();
        if let (Some(runs), Some(own)) = (runs, own) {
            let judged = points_of(&runs);
            let p = &t["expected"]["points"];
            let expected = p["mean"].as_f64();
            let held = (p["judged_low"].as_f64().zip(p["judged_high"].as_f64()))
                .map(|(lo, hi)| judged >= lo - 1e-9 && judged <= hi + 1e-9);
            out.push(Row {
                expected,
                held,
                own,
                judged,
                runs,
            });
        }
    }
    Ok(out)
}

fn main() -> anyhow::Result<()> {
    let folders = campaign_folders("expected_vs_judged")?;
    let extra = extra_judged()?;
    let mut all = Vec::new();
    for folder in &folders {
        let rows = rows_of(folder, &extra)?;
        let gap = median(rows.iter().map(|r| mean(&r.runs) - mean(&r.own)).collect());
        let sum = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() + 0.0;
        let held = rows.iter().filter(|r| r.held == Some(true)).count();
        let intervals = rows.iter().filter(|r| r.held.is_some()).count();
        println!(
            "{}: {} tests; points expected {:.2}, own flights {:.2}, judged {:.2}; judged inside the interval \
             {held} of {intervals}; evaluation - campaign distance: median {gap:.3} m",
            folder.display(),
            rows.len(),
            sum(&|r| r.expected.unwrap_or(0.0)),
            sum(&|r| points_of(&r.own)),
            sum(&|r| r.judged),
        );
        all.extend(rows);
    }
    let own_m: Vec<f64> = all.iter().map(|r| mean(&r.own)).collect();
    let judged_m: Vec<f64> = all.iter().map(|r| mean(&r.runs)).collect();
    let sd = |v: &[f64]| (v.iter().map(|d| (d - mean(v)).powi(2)).sum::<f64>() / (v.len() as f64 - 1.0)).sqrt();
    let show = |s: Option<f64>| s.map_or("-".into(), |s| format!("{s:.3}"));
    println!(
        "{} tests: campaign mean distance ranks the evaluation mean with Spearman {}; evaluation flights' sd: median {:.3} m",
        all.len(),
        show(spearman(&own_m, &judged_m)),
        median(all.iter().map(|r| sd(&r.runs)).collect())
    );
    let with: Vec<&Row> = all.iter().filter(|r| r.expected.is_some()).collect();
    let judged: Vec<f64> = with.iter().map(|r| r.judged).collect();
    let expected: Vec<f64> = with.iter().filter_map(|r| r.expected).collect();
    let own: Vec<f64> = with.iter().map(|r| points_of(&r.own)).collect();
    let gaps: Vec<f64> = expected.iter().zip(&judged).map(|(e, j)| e - j).collect();
    println!(
        "{} tests with expected points: judged mean {:.3}; expected points mean {:.3}, Spearman {}, MAE {:.3}, \
         mean error {:+.3}; own flights' points mean {:.3}, Spearman {}",
        with.len(),
        mean(&judged),
        mean(&expected),
        show(spearman(&expected, &judged)),
        mean(&gaps.iter().map(|g| g.abs()).collect::<Vec<_>>()),
        mean(&gaps),
        mean(&own),
        show(spearman(&own, &judged))
    );
    Ok(())
}
