//! Chooses the expected-points constants (`src/campaign/plan/expected_points.rs`: the prior's weight, a
//! neighbour flight's weight and the neighbours' cap) by cross-validation with folds by obstacle set, on
//! tests flown many times: each test's first K flights (K = 1-3, what a campaign has) are shown, the mean
//! points of its next 5 flights (what the 2026 judge scores) are predicted.
//!
//! ```sh
//! cargo run --example fit_expected -- export CAMPAIGN TESTS     # every flown candidate as TESTS/test_<id>.yaml
//! prgenuav evaluate TESTS --runs 8                              # 3 shown + 5 judged flights per test
//! cargo run --example fit_expected -- collect CAMPAIGN DATA.json TESTS/evaluation/report.json [REPORT.json...]
//! cargo run --example fit_expected -- cv DATA.json [DATA.json ...]
//! ```
//!
//! `collect` also takes evaluations of the tests the campaign wrote (`evaluate CAMPAIGN --runs 8`). It keeps
//! what the fit reads (per test: obstacles, the campaign's prediction, the evaluated
//! distances), small enough for `tests/data/expected-points/`.

#[path = "common/expected_cv.rs"]
mod expected_cv;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use anyhow::Context;
use prgenuav::campaign::store::journal::Journal;
use prgenuav::model::{Spelling, TestCase};

use expected_cv::{Case, DataFile};

/// Writes every candidate the campaign in `campaign` flew as `out/test_<candidate>.yaml`.
fn export(campaign: &Path, out: &Path) -> anyhow::Result<()> {
    let settings: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(campaign.join("campaign.json"))?)?;
    let case = settings["case"].as_str().context("campaign.json: no case")?;
    let case = TestCase::load(Path::new(case))?.with_absolute_references()?;
    std::fs::create_dir_all(out)?;
    let mut written = 0;
    for r in Journal::read(&campaign.join("journal.jsonl"))? {
        let path = out.join(format!("test_{}.yaml", r.candidate.0));
        if r.attempt == 0 && !path.exists() {
            case.with_obstacles(r.obstacles.clone()).save(&path, Spelling::New)?;
            written += 1;
        }
    }
    println!("{written} tests written to {}", out.display());
    Ok(())
}

/// The candidate id of a test YAML: a test a campaign wrote (its folder's report.json names it), or a
/// `test_<id>.yaml` written by `export`.
fn candidate_of(test: &Path) -> anyhow::Result<Option<u64>> {
    let name = test.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    let written = written_tests(test.parent().unwrap_or(Path::new(".")))?;
    if !written.is_empty() {
        return Ok(written.get(name).copied());
    }
    Ok(name
        .strip_prefix("test_")
        .and_then(|n| n.strip_suffix(".yaml")?.parse().ok()))
}

/// The tests a campaign wrote, by file name: `reported_as` of its report.json's tests (none without one).
fn written_tests(folder: &Path) -> anyhow::Result<HashMap<String, u64>> {
    let Ok(text) = std::fs::read_to_string(folder.join("report.json")) else {
        return Ok(HashMap::new());
    };
    let json: serde_json::Value = serde_json::from_str(&text)?;
    let tests = json["tests"].as_array().map(Vec::as_slice).unwrap_or_default();
    Ok(tests
        .iter()
        .filter_map(|t| Some((t["reported_as"].as_str()?.to_string(), t["candidate"].as_u64()?)))
        .collect())
}

/// Joins the campaign's journal (obstacles, prediction of each candidate's first flight) with evaluations of
/// its tests (the flown distances, in run order; a test in several evaluations gets their runs one after
/// the other) into `out`.
fn collect(campaign: &Path, out: &Path, reports: &[PathBuf]) -> anyhow::Result<()> {
    let mut cases: BTreeMap<u64, Case> = BTreeMap::new();
    for r in Journal::read(&campaign.join("journal.jsonl"))? {
        // A test flown unscreened has no prediction to weigh: NaN, as the expectation takes it.
        if r.attempt == 0 {
            let predicted_m = r.predicted_m().unwrap_or(f64::NAN);
            let case = Case {
                candidate: r.candidate.0,
                obstacles: r.obstacles,
                predicted_m,
                runs: Vec::new(),
            };
            cases.insert(r.candidate.0, case);
        }
    }
    for report in reports {
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report)?)?;
        let tests = json["tests"].as_array().context("report.json: no tests[]")?;
        for t in tests {
            let test = Path::new(t["test"].as_str().context("a test without its YAML")?);
            let id = candidate_of(test)?.with_context(|| format!("{}: not a test of the campaign", test.display()))?;
            let case = cases
                .get_mut(&id)
                .with_context(|| format!("candidate {id}: not in the journal"))?;
            let runs = t["runs"].as_array().context("a test without runs[]")?;
            case.runs.extend(runs.iter().filter_map(|r| r["min_distance"].as_f64()));
        }
    }
    let data = DataFile {
        source: format!("{} + {reports:?}", campaign.display()),
        cases: cases.into_values().filter(|c| !c.runs.is_empty()).collect(),
    };
    prgenuav::io::write_json(out, &data, true)?;
    println!("{} tests with runs written to {}", data.cases.len(), out.display());
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = |i: usize| args.get(i).map(PathBuf::from);
    match (args.first().map(String::as_str), path(1), path(2), path(3)) {
        (Some("export"), Some(campaign), Some(out), None) => export(&campaign, &out),
        (Some("collect"), Some(campaign), Some(out), Some(_)) => {
            let reports: Vec<PathBuf> = args[3..].iter().map(PathBuf::from).collect();
            collect(&campaign, &out, &reports)
        }
        (Some("cv"), Some(_), ..) => expected_cv::run(&args[1..]),
        _ => anyhow::bail!(
            "usage: fit_expected export CAMPAIGN TESTS | collect CAMPAIGN DATA.json REPORT.json... | cv DATA.json..."
        ),
    }
}
