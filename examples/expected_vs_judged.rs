//! How well a campaign's figures foretell the judge: for every written test of campaign folders that were
//! evaluated (`evaluate CAMPAIGN --runs 5`), its expected points, its own campaign flights and its evaluation
//! flights. Prints each folder's sums and the median gap between a test's evaluation and campaign distances;
//! then, over all tests, how the campaign's figures rank the judged means (Spearman) and how much a test's
//! evaluation flights scatter.
//!
//! ```sh
//! cargo run --profile test --example expected_vs_judged -- CAMPAIGN...
//! ```

use std::collections::HashMap;
use std::path::Path;

use anyhow::Context;
use prgenuav::campaign::store::journal::Journal;
use prgenuav::judge::points;
use prgenuav::lfs::fidelity::spearman;

#[path = "common/evaluation_report.rs"]
mod evaluation_report;
use evaluation_report::{campaign_folders, evaluated_tests};

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

/// Judged mean points and run distances by test file name.
fn judged(folder: &Path) -> anyhow::Result<HashMap<String, (f64, Vec<f64>)>> {
    let tests = evaluated_tests(folder)?.with_context(|| format!("{}: no evaluation", folder.display()))?;
    let judged = |t: &serde_json::Value| {
        let runs = t["runs"].as_array().map(Vec::as_slice).unwrap_or_default();
        let runs: Vec<f64> = runs.iter().filter_map(|r| r["min_distance"].as_f64()).collect();
        Some((t["mean_points"].as_f64()?, runs))
    };
    Ok(tests
        .into_iter()
        .filter_map(|(name, t)| Some((name, judged(&t)?)))
        .collect())
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

fn rows_of(folder: &Path) -> anyhow::Result<Vec<Row>> {
    let text = std::fs::read_to_string(folder.join("report.json"))?;
    let json: serde_json::Value = serde_json::from_str(&text)?;
    let (judged, own) = (judged(folder)?, own_flights(folder)?);
    let mut out = Vec::new();
    for t in json["tests"].as_array().context("report.json: no tests[]")? {
        let name = t["reported_as"].as_str().unwrap_or_default();
        let own = t["candidate"].as_u64().and_then(|c| own.get(&c).cloned());
        if let (Some((judged, runs)), Some(own)) = (judged.get(name).cloned(), own) {
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
    let mut all = Vec::new();
    for folder in &folders {
        let rows = rows_of(folder)?;
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
    println!(
        "{} tests with expected points: judged mean {:.3}; expected points mean {:.3}, Spearman {}; own flights' points mean {:.3}, Spearman {}",
        with.len(),
        mean(&judged),
        mean(&expected),
        show(spearman(&expected, &judged)),
        mean(&own),
        show(spearman(&own, &judged))
    );
    Ok(())
}
