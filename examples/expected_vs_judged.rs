//! How well a campaign's figures foretell the judge: for every written test of campaign folders that were
//! evaluated (`evaluate CAMPAIGN --runs 5`), its expected points, the mean points of its own campaign flights
//! and the judged mean points of its evaluation flights. Prints each folder's sums and, over all tests, the
//! Spearman correlation of each campaign figure with the judged mean, and the mean of each.
//!
//! ```sh
//! cargo run --profile test --example expected_vs_judged -- CAMPAIGN...
//! ```

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use prgenuav::campaign::store::journal::Journal;
use prgenuav::judge::points;
use prgenuav::lfs::fidelity::spearman;

/// One written, evaluated test.
struct Row {
    expected: f64,
    own: f64,
    judged: f64,
}

/// Judged mean points by test file name.
fn judged(folder: &Path) -> anyhow::Result<HashMap<String, f64>> {
    let path = folder.join("evaluation/report.json");
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let json: serde_json::Value = serde_json::from_str(&text)?;
    let mut out = HashMap::new();
    for t in json["tests"].as_array().context("evaluation: no tests[]")? {
        let name = t["test"].as_str().and_then(|p| Path::new(p).file_name()?.to_str());
        if let (Some(name), Some(mean)) = (name, t["mean_points"].as_f64()) {
            out.insert(name.to_string(), mean);
        }
    }
    Ok(out)
}

/// Mean points of each candidate's charged campaign flights.
fn own_points(folder: &Path) -> anyhow::Result<HashMap<u64, f64>> {
    let path = folder.join("journal.jsonl");
    let records = Journal::read(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut sums: HashMap<u64, (f64, f64)> = HashMap::new();
    for r in &records {
        let Some(d) = r.flown.min_distance else { continue };
        let e = sums.entry(r.candidate.0).or_default();
        *e = (e.0 + f64::from(points(d)), e.1 + 1.0);
    }
    Ok(sums.into_iter().map(|(c, (p, n))| (c, p / n)).collect())
}

fn rows_of(folder: &Path) -> anyhow::Result<Vec<Row>> {
    let text = std::fs::read_to_string(folder.join("report.json"))?;
    let json: serde_json::Value = serde_json::from_str(&text)?;
    let (judged, own) = (judged(folder)?, own_points(folder)?);
    let mut out = Vec::new();
    for t in json["tests"].as_array().context("report.json: no tests[]")? {
        let name = t["reported_as"].as_str().unwrap_or_default();
        let expected = t["expected"]["points"]["mean"].as_f64();
        let own = t["candidate"].as_u64().and_then(|c| own.get(&c).copied());
        if let (Some(judged), Some(expected), Some(own)) = (judged.get(name).copied(), expected, own) {
            out.push(Row { expected, own, judged });
        }
    }
    Ok(out)
}

fn main() -> anyhow::Result<()> {
    let folders: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    anyhow::ensure!(!folders.is_empty(), "usage: expected_vs_judged CAMPAIGN...");
    let mut all = Vec::new();
    for folder in &folders {
        let rows = rows_of(folder)?;
        let sum = |f: fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() + 0.0;
        println!(
            "{}: {} tests; points expected {:.2}, own flights {:.2}, judged {:.2}",
            folder.display(),
            rows.len(),
            sum(|r| r.expected),
            sum(|r| r.own),
            sum(|r| r.judged)
        );
        all.extend(rows);
    }
    let judged: Vec<f64> = all.iter().map(|r| r.judged).collect();
    let n = all.len().max(1) as f64;
    println!(
        "{} tests; judged mean points {:.3}",
        all.len(),
        judged.iter().sum::<f64>() / n
    );
    for (name, f) in [
        ("expected points", (|r: &Row| r.expected) as fn(&Row) -> f64),
        ("own flights' points", |r| r.own),
    ] {
        let v: Vec<f64> = all.iter().map(f).collect();
        let rho = spearman(&v, &judged).map_or("-".into(), |s| format!("{s:.3}"));
        println!(
            "{name}: mean {:.3}, Spearman with the judged mean {rho}",
            v.iter().sum::<f64>() / n
        );
    }
    Ok(())
}
