//! How far the DTW distance between two tests' averages of their first K flights (K = 1-3: what a campaign
//! has when its trajectory guard compares them) lies from the DTW distance between averages of 5 other
//! flights of the same tests (what the 2026 judge compares): the data the guard's margin
//! (`GUARD_MARGIN` in `src/campaign/report/expected/trajectory_guard.rs`) was chosen from.
//!
//! Reads evaluations' report.json made with `evaluate --runs 8` or more (pairs within each): runs 1-K are the campaign's
//! flights, runs 4-8 the judge's. Prints, per K, the quantiles of judge / campaign distance over the pairs
//! whose campaign distance lies within 40-400 m (the pairs a guard at 75 m could misjudge), and, per guard
//! threshold, the pairs it lets through that the judge would find similar at 75 m.
//!
//! ```sh
//! cargo run --profile test --example guard_margin -- REPORT.json...
//! ```

use std::path::PathBuf;

use anyhow::Context;
use prgenuav::judge::similarity::SIMILAR_BELOW_M;
use prgenuav::judge::similarity::{average, path_distance, prepare};
use prgenuav::model::{Trajectory, load_flight};

const SHOWN: [usize; 3] = [1, 2, 3];
const JUDGED: usize = 5;
const WINDOW_M: (f64, f64) = (40.0, 400.0);
const THREADS: usize = 2;
const GUARDS_M: [f64; 8] = [75.0, 85.0, 90.0, 100.0, 110.0, 125.0, 150.0, 200.0];

/// A test's averages: of its first 1, 2 and 3 flights, and of its next 5.
struct Averages {
    shown: Vec<Trajectory>,
    judged: Trajectory,
}

fn averages_of(runs: &[PathBuf]) -> anyhow::Result<Option<Averages>> {
    let mut flights = Vec::new();
    for r in runs {
        flights.push(prepare(&load_flight(r)?));
    }
    let last = SHOWN[SHOWN.len() - 1];
    let Some(judged) = average(&flights[last..last + JUDGED]) else {
        return Ok(None);
    };
    let shown: Option<Vec<Trajectory>> = SHOWN.iter().map(|&k| average(&flights[..k])).collect();
    Ok(shown.map(|shown| Averages { shown, judged }))
}

fn quantile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

/// Each test's flight files, in run order (tests with too few runs left out).
fn tests(report: &str) -> anyhow::Result<Vec<Vec<PathBuf>>> {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report)?)?;
    let tests = json["tests"].as_array().context("report.json: no tests[]")?;
    let runs = |t: &serde_json::Value| -> Vec<PathBuf> {
        let r = t["runs"].as_array().map(Vec::as_slice).unwrap_or_default();
        r.iter()
            .filter_map(|r| r["trajectory"].as_str().map(PathBuf::from))
            .collect()
    };
    Ok(tests
        .iter()
        .map(runs)
        .filter(|r| r.len() >= SHOWN[2] + JUDGED)
        .collect())
}

/// The margin at which a pair at the guard's threshold stays apart on the judge's averages 90 % (80 %) of
/// the time: 1 over the 10 % (20 %) quantile of judge / campaign distance, K pooled.
fn suggested_margin(pairs: &[(Vec<f64>, f64)]) {
    let mut pooled: Vec<f64> = (0..SHOWN.len())
        .flat_map(|ki| {
            pairs
                .iter()
                .filter(move |(c, _)| (WINDOW_M.0..WINDOW_M.1).contains(&c[ki]))
                .map(move |(c, j)| j / c[ki])
        })
        .collect();
    pooled.sort_by(f64::total_cmp);
    if !pooled.is_empty() {
        let (p10, p20) = (quantile(&pooled, 0.1), quantile(&pooled, 0.2));
        println!(
            "K 1-3 pooled, {} ratios: p10 {p10:.3} (margin 1/p10 = {:.2}), p20 {p20:.3} (margin {:.2})",
            pooled.len(),
            1.0 / p10,
            1.0 / p20
        );
    }
}

fn report(pairs: &[(Vec<f64>, f64)]) {
    let t = SIMILAR_BELOW_M;
    for (ki, k) in SHOWN.iter().enumerate() {
        let mut ratios: Vec<f64> = (pairs.iter())
            .filter(|(c, _)| (WINDOW_M.0..WINDOW_M.1).contains(&c[ki]))
            .map(|(c, j)| j / c[ki])
            .collect();
        ratios.sort_by(f64::total_cmp);
        if ratios.is_empty() {
            println!("K {k}: no pair within {WINDOW_M:?} m");
            continue;
        }
        let q = |p: f64| quantile(&ratios, p);
        println!(
            "K {k}: judge / campaign DTW over {} pairs: p5 {:.3}, p10 {:.3}, p25 {:.3}, median {:.3}, p75 {:.3}, p90 {:.3}",
            ratios.len(),
            q(0.05),
            q(0.1),
            q(0.25),
            q(0.5),
            q(0.75),
            q(0.9)
        );
        for g in GUARDS_M {
            let through: Vec<&(Vec<f64>, f64)> = pairs.iter().filter(|(c, _)| c[ki] >= g).collect();
            let leak = through.iter().filter(|(_, j)| *j < t).count();
            let near: Vec<_> = through.iter().filter(|(c, _)| c[ki] < 1.5 * g).collect();
            let near_leak = near.iter().filter(|(_, j)| *j < t).count();
            let held = pairs.iter().filter(|(c, j)| c[ki] < g && *j >= t).count();
            println!(
                "  guard {g} m: let through {} pairs, {leak} similar on 5-flight averages; of them within \
                 {g}-{} m {} pairs, {near_leak} similar; set aside although apart on averages: {held}",
                through.len(),
                1.5 * g,
                near.len()
            );
        }
    }
    suggested_margin(pairs);
    let similar = pairs.iter().filter(|(_, j)| *j < t).count();
    println!(
        "pairs: {}, similar on 5-flight averages at {t} m: {similar}",
        pairs.len()
    );
}

/// The pairs of one evaluation: each pair's campaign distances (per K) and its judge distance.
fn pairs_of(report_path: &str) -> anyhow::Result<Vec<(Vec<f64>, f64)>> {
    let tests = tests(report_path)?;
    let per = tests.len().div_ceil(THREADS).max(1);
    let mut averages: Vec<Option<Averages>> = Vec::new();
    std::thread::scope(|s| -> anyhow::Result<()> {
        let handles: Vec<_> = (tests.chunks(per))
            .map(|chunk| s.spawn(move || chunk.iter().map(|r| averages_of(r)).collect::<Vec<_>>()))
            .collect();
        for h in handles {
            for a in h.join().map_err(|_| anyhow::anyhow!("an averaging thread panicked"))? {
                averages.push(a?);
            }
        }
        Ok(())
    })?;
    let averages: Vec<Averages> = averages.into_iter().flatten().collect();
    println!(
        "{report_path}: tests with {} runs or more: {}",
        SHOWN[2] + JUDGED,
        averages.len()
    );
    let mut pairs = Vec::new();
    for i in 0..averages.len() {
        for j in i + 1..averages.len() {
            let (a, b) = (&averages[i], &averages[j]);
            let shown: Option<Vec<f64>> = (0..SHOWN.len())
                .map(|k| path_distance(&a.shown[k], &b.shown[k]))
                .collect();
            if let (Some(shown), Some(judged)) = (shown, path_distance(&a.judged, &b.judged)) {
                pairs.push((shown, judged));
            }
        }
    }
    Ok(pairs)
}

fn main() -> anyhow::Result<()> {
    let reports: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(!reports.is_empty(), "usage: guard_margin REPORT.json...");
    let mut pairs = Vec::new();
    for r in &reports {
        pairs.extend(pairs_of(r)?);
    }
    report(&pairs);
    Ok(())
}
