//! How far apart two averages of the *same* test's flights lie, against two different tests' averages:
//! the data `evaluate --similar-below` was chosen from (docs/evaluate.md).
//!
//! Reads an evaluation's report.json made with `evaluate --runs 2K`: each test's runs are split into two
//! halves of K (first and second), each half averaged as the competition averages 5 flights; prints the
//! quantiles of the same-test distances (half against half) and of the different-test distances (first
//! halves).
//!
//! ```sh
//! cargo run --release --example similar_threshold -- FOLDER/evaluation/report.json
//! ```

use std::path::PathBuf;

use prgenuav::judge::similarity::{average, path_distance, prepare};
use prgenuav::model::{Trajectory, load_flight};

fn quantiles(mut v: Vec<f64>) -> String {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return "none".into();
    }
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    format!(
        "n {}, min {:.1}, p5 {:.1}, p25 {:.1}, median {:.1}, p75 {:.1}, p95 {:.1}, max {:.1}",
        v.len(),
        q(0.0),
        q(0.05),
        q(0.25),
        q(0.5),
        q(0.75),
        q(0.95),
        q(1.0)
    )
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let report = std::env::args().nth(1).ok_or("usage: similar_threshold REPORT.json")?;
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report)?)?;
    let tests = json["tests"].as_array().ok_or("report.json: no tests[]")?;
    let mut halves: Vec<(Trajectory, Trajectory)> = Vec::new();
    for t in tests {
        let runs: Vec<PathBuf> = t["runs"]
            .as_array()
            .ok_or("a test without runs[]")?
            .iter()
            .filter_map(|r| r["trajectory"].as_str().map(PathBuf::from))
            .collect();
        if runs.len() < 2 {
            continue;
        }
        let k = runs.len() / 2;
        let mut flights = Vec::new();
        for r in &runs[..2 * k] {
            flights.push(prepare(&load_flight(r)?));
        }
        let (a, b) = flights.split_at(k);
        if let (Some(a), Some(b)) = (average(a), average(b)) {
            halves.push((a, b));
        }
    }
    let same: Vec<f64> = halves.iter().filter_map(|(a, b)| path_distance(a, b)).collect();
    let mut different = Vec::new();
    for i in 0..halves.len() {
        for j in i + 1..halves.len() {
            different.extend(path_distance(&halves[i].0, &halves[j].0));
        }
    }
    println!("tests: {}", halves.len());
    for t in [50.0, 75.0, 100.0, 150.0, 200.0, 300.0] {
        let below = |v: &[f64]| v.iter().filter(|d| **d < t).count();
        println!(
            "below {t} m: same test {} of {}, different tests {} of {}",
            below(&same),
            same.len(),
            below(&different),
            different.len()
        );
    }
    println!("same test, half against half (DTW m): {}", quantiles(same));
    println!("different tests (DTW m): {}", quantiles(different));
    Ok(())
}
