//! The trajectory guard on a flown campaign: for every pair of its failing tests, the DTW distance between
//! the averages of their campaign flights (what the guard compares) and, where the campaign's written tests
//! were evaluated (`evaluate CAMPAIGN --runs 5`), the distance between the averages of their evaluation
//! flights (what the judge compares). Prints the pairs with a campaign distance below 200 m, each test's
//! expected score (NaN from a campaign that had none), the guard's verdict, and the judge / campaign ratio of the evaluated pairs.
//!
//! ```sh
//! cargo run --profile test --example guard_campaign -- CAMPAIGN...
//! ```
//!
//! A report whose flight paths are relative resolves them from the working directory: run it from where that
//! evaluation ran.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use prgenuav::judge::similarity::{average, path_distance, prepare};
use prgenuav::model::{Trajectory, load_flight};

#[path = "common/evaluation_report.rs"]
mod evaluation_report;
use evaluation_report::{campaign_folders, evaluated_tests};

const SHOWN_BELOW_M: f64 = 200.0;

struct Test {
    name: String,
    score: f64,
    copies: Option<String>,
    campaign: Option<Trajectory>,
    judged: Option<Trajectory>,
}

fn average_of(files: &[PathBuf]) -> anyhow::Result<Option<Trajectory>> {
    let mut flights = Vec::new();
    for f in files {
        flights.push(prepare(&load_flight(f)?));
    }
    Ok(average(&flights))
}

/// Each evaluated test's run files, by the test's file name.
fn evaluated(folder: &Path) -> anyhow::Result<HashMap<String, Vec<PathBuf>>> {
    let tests = evaluated_tests(folder)?.unwrap_or_default();
    let files = |t: &serde_json::Value| -> Vec<PathBuf> {
        let runs = t["runs"].as_array().map(Vec::as_slice).unwrap_or_default();
        runs.iter()
            .filter_map(|r| r["trajectory"].as_str().map(PathBuf::from))
            .collect()
    };
    Ok(tests.into_iter().map(|(name, t)| (name, files(&t))).collect())
}

fn tests_of(folder: &Path) -> anyhow::Result<Vec<Test>> {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(folder.join("report.json"))?)?;
    let judged = evaluated(folder)?;
    let mut out = Vec::new();
    for t in json["tests"].as_array().context("report.json: no tests[]")? {
        let Some(name) = t["reported_as"].as_str().map(str::to_string) else {
            continue;
        };
        let score = t["expected"]["score"].as_f64().unwrap_or(f64::NAN);
        let own: Vec<PathBuf> = (t["trajectories"].as_array().map(Vec::as_slice).unwrap_or_default())
            .iter()
            .filter_map(|p| Some(folder.join(p.as_str()?)))
            .filter(|p| p.exists())
            .collect();
        let runs = judged.get(&name).map(Vec::as_slice).unwrap_or_default();
        out.push(Test {
            score,
            copies: t["near_duplicate_of"].as_str().map(str::to_string),
            campaign: average_of(&own)?,
            judged: if runs.is_empty() { None } else { average_of(runs)? },
            name,
        });
    }
    Ok(out)
}

fn main() -> anyhow::Result<()> {
    let folders = campaign_folders("guard_campaign")?;
    let mut ratios = Vec::new();
    for folder in &folders {
        let tests = tests_of(folder)?;
        println!("{}: {} reported tests", folder.display(), tests.len());
        for (i, a) in tests.iter().enumerate() {
            for b in &tests[i + 1..] {
                let Some(c) = a
                    .campaign
                    .as_ref()
                    .zip(b.campaign.as_ref())
                    .and_then(|(x, y)| path_distance(x, y))
                else {
                    continue;
                };
                let j = a
                    .judged
                    .as_ref()
                    .zip(b.judged.as_ref())
                    .and_then(|(x, y)| path_distance(x, y));
                if let Some(j) = j {
                    ratios.push((c, j));
                }
                if c < SHOWN_BELOW_M || j.is_some() {
                    let verdict = |t: &Test| t.copies.as_ref().map_or(String::new(), |k| format!(" (copies {k})"));
                    println!(
                        "  {} {:.2}{} / {} {:.2}{}: campaign {c:.1} m, judge {}",
                        a.name,
                        a.score,
                        verdict(a),
                        b.name,
                        b.score,
                        verdict(b),
                        j.map_or("-".into(), |j| format!("{j:.1} m"))
                    );
                }
            }
        }
    }
    ratios.sort_by(|x, y| (x.1 / x.0).total_cmp(&(y.1 / y.0)));
    let r: Vec<f64> = ratios.iter().map(|(c, j)| j / c).collect();
    if !r.is_empty() {
        let q = |p: f64| r[((r.len() - 1) as f64 * p).round() as usize];
        println!(
            "judge / campaign over {} evaluated pairs: p10 {:.3}, p25 {:.3}, median {:.3}, p75 {:.3}, p90 {:.3}",
            r.len(),
            q(0.1),
            q(0.25),
            q(0.5),
            q(0.75),
            q(0.9)
        );
    }
    Ok(())
}
