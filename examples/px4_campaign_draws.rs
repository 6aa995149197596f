//! Do the LFS and the mock fly the campaign's own tests like PX4? Reads the PX4 flights of ten budget-100
//! campaigns (`tests/data/px4-campaign-draws/tests.jsonl`: PX4 v1.14 SIH, missions 2 and 5; one line per test
//! with its obstacles and every PX4 flight of it), predicts each test with the LFS (`px4` motion model, as
//! `generate` screens) and flies it on the embedded mock with the campaign's mock profile. Prints, per kind of
//! draw (`no-screen`: the generator's plain draws; `learning`: what the learning campaigns chose to fly) and
//! mission: the share of first flights below 1.5 m on PX4, on the mock and by the LFS, the medians, and how
//! each model orders PX4's first flights (Spearman) and separates its failures (ROC AUC of the distance).
//!
//! `cargo run --release --example px4_campaign_draws -- [PARALLEL=2]` (about 25 minutes on 2 cores; env
//! `NO_MOCK=1`: the LFS alone, about 3 minutes; `MOCK_PROFILE=NAME` or `MOCK_SETTING=...`: that mock profile or
//! setting, as `mock_fit` takes them; `ONLY=no-screen` or `ONLY=learning`: those tests only; `DATA=FILE`: that
//! file instead)
//!
//! `... -- collect OUT.jsonl MISSION DRAWS FOLDER`: appends the tests of one `generate` folder (its
//! `journal.jsonl`: every charged flight of a candidate, in journal order) to OUT.jsonl, labelled `DRAWS`
//! (`learning` or `no-screen`); a candidate whose first flight did not land is left out.

#[path = "common/mock_flight.rs"]
mod mock_flight;
#[path = "common/setting.rs"]
mod setting;

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use anyhow::Context;
use prgenuav::bridge::predict;
use prgenuav::lfs::fidelity::aggregate;
use prgenuav::lfs::sim::MotionModel;
use prgenuav::model::competition::FAIL_BELOW_M;
use prgenuav::model::{Obstacle, TestCase};
use serde::Deserialize;
use tokio::sync::Semaphore;

const DATA: &str = "tests/data/px4-campaign-draws/tests.jsonl";

/// One test of a PX4 campaign.
#[derive(Debug, Clone, Deserialize)]
struct Row {
    mission: u32,
    draws: String,
    obstacles: Vec<Obstacle>,
    /// Every PX4 flight of it, metres, the first first.
    px4_min_distance: Vec<f64>,
}

/// A test's first PX4 flight and the two models' distances.
struct Judged {
    px4: f64,
    lfs: Option<f64>,
    mock: Option<f64>,
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("collect") {
        return collect(&args[1..]);
    }
    let parallel: usize = args.first().map_or(Ok(2), |a| a.parse())?;
    let with_mock = std::env::var_os("NO_MOCK").is_none();
    let data = std::env::var("DATA").unwrap_or_else(|_| DATA.to_string());
    let text = std::fs::read_to_string(&data).with_context(|| format!("reading {data}"))?;
    let mut rows: Vec<Row> = (text.lines().enumerate())
        .map(|(i, l)| serde_json::from_str(l).with_context(|| format!("{data}:{}", i + 1)))
        .collect::<anyhow::Result<_>>()?;
    if let Ok(only) = std::env::var("ONLY") {
        rows.retain(|r| r.draws == only);
    }
    let motion = MotionModel::by_name("px4").context("the px4 motion model")?;
    let rt = tokio::runtime::Runtime::new()?;
    let gate = Arc::new(Semaphore::new(parallel.max(1)));
    let judged = rt.block_on(async {
        let mut handles = Vec::new();
        for (seed, row) in (0u64..).zip(&rows) {
            let case = TestCase::load(Path::new(&format!("missions/mission{}.yaml", row.mission)))?;
            let test = case.with_obstacles(row.obstacles.clone());
            let px4 = *row.px4_min_distance.first().context("a test without a PX4 flight")?;
            let gate = gate.clone();
            handles.push(tokio::spawn(async move {
                let _permit = gate.acquire_owned().await?;
                let lfs = predict(&test, motion, Default::default())
                    .ok()
                    .and_then(|p| p.min_distance);
                let mock = if with_mock {
                    let (status, d, _) = mock_flight::fly_mock(test, seed).await?;
                    d.filter(|_| status == "landed")
                } else {
                    None
                };
                anyhow::Ok(Judged { px4, lfs, mock })
            }));
        }
        let mut out = Vec::new();
        for h in handles {
            out.push(h.await??);
        }
        anyhow::Ok(out)
    })?;
    let mut groups: BTreeMap<(String, u32), Vec<&Judged>> = BTreeMap::new();
    for (row, j) in rows.iter().zip(&judged) {
        groups.entry((row.draws.clone(), row.mission)).or_default().push(j);
    }
    println!(
        "| draws | mission | tests | below 1.5 m: PX4 / mock / LFS | median m: PX4 / mock / LFS | Spearman vs PX4: \
         mock / LFS | AUC of PX4's failures: mock / LFS |"
    );
    println!("|---|---|---|---|---|---|---|");
    for ((draws, mission), js) in &groups {
        let px4: Vec<f64> = js.iter().map(|j| j.px4).collect();
        let mock: Vec<(f64, f64)> = js.iter().filter_map(|j| j.mock.map(|m| (m, j.px4))).collect();
        let lfs: Vec<(f64, f64)> = js.iter().filter_map(|j| j.lfs.map(|m| (m, j.px4))).collect();
        let model: Vec<f64> = mock.iter().map(|p| p.0).collect();
        let lfs_m: Vec<f64> = lfs.iter().map(|p| p.0).collect();
        println!(
            "| {draws} | {mission} | {} | {} / {} / {} | {} / {} / {} | {} / {} | {} / {} |",
            js.len(),
            rate(&px4),
            rate(&model),
            rate(&lfs_m),
            median(&px4),
            median(&model),
            median(&lfs_m),
            show(aggregate(&mock).spearman),
            show(aggregate(&lfs).spearman),
            show(auc(&mock)),
            show(auc(&lfs))
        );
    }
    Ok(())
}

fn show(x: Option<f64>) -> String {
    x.map_or("-".into(), |x| format!("{x:.2}"))
}

fn rate(v: &[f64]) -> String {
    let below = v.iter().filter(|d| **d < FAIL_BELOW_M).count();
    show((!v.is_empty()).then(|| below as f64 / v.len() as f64))
}

fn median(v: &[f64]) -> String {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    show(v.get(v.len() / 2).copied())
}

/// ROC AUC of a model's distance (closer = likelier to fail) against PX4's first flight failing, over
/// `(model, px4)` pairs; ties count half.
fn auc(pairs: &[(f64, f64)]) -> Option<f64> {
    let (fail, pass): (Vec<_>, Vec<_>) = pairs.iter().partition(|(_, px4)| *px4 < FAIL_BELOW_M);
    if fail.is_empty() || pass.is_empty() {
        return None;
    }
    let wins: f64 = (fail.iter())
        .flat_map(|(f, _)| pass.iter().map(move |(p, _)| (f, p)))
        .map(|(f, p)| match f.total_cmp(p) {
            std::cmp::Ordering::Less => 1.0,
            std::cmp::Ordering::Equal => 0.5,
            std::cmp::Ordering::Greater => 0.0,
        })
        .sum();
    Some(wins / (fail.len() * pass.len()) as f64)
}

/// One journal line, as much of it as a test's row needs.
#[derive(Deserialize)]
struct Flown {
    candidate: u64,
    obstacles: Vec<Obstacle>,
    min_distance: Option<f64>,
    status: String,
}

/// A flight's status and distance.
type Flight = (String, Option<f64>);

/// `collect OUT.jsonl MISSION DRAWS FOLDER`: one row per candidate of the folder's journal.
fn collect(args: &[String]) -> anyhow::Result<()> {
    let [out, mission, draws, folder] = args else {
        anyhow::bail!("usage: collect OUT.jsonl MISSION DRAWS FOLDER");
    };
    let mission: u32 = mission.parse().context("MISSION: a number")?;
    let journal = Path::new(folder).join("journal.jsonl");
    let text = std::fs::read_to_string(&journal).with_context(|| format!("reading {}", journal.display()))?;
    let mut tests: BTreeMap<u64, (Vec<Obstacle>, Vec<Flight>)> = BTreeMap::new();
    for (i, line) in text.lines().enumerate() {
        let f: Flown = serde_json::from_str(line).with_context(|| format!("{}:{}", journal.display(), i + 1))?;
        let entry = tests.entry(f.candidate).or_insert_with(|| (f.obstacles, Vec::new()));
        entry.1.push((f.status, f.min_distance));
    }
    let mut lines = String::new();
    for (candidate, (obstacles, flights)) in &tests {
        if flights.first().is_none_or(|(s, d)| s != "landed" || d.is_none()) {
            continue;
        }
        let landed: Vec<f64> = flights
            .iter()
            .filter(|(s, _)| s == "landed")
            .filter_map(|f| f.1)
            .collect();
        let row = serde_json::json!({
            "mission": mission, "campaign": folder, "draws": draws, "candidate": candidate,
            "obstacles": obstacles, "px4_min_distance": landed,
        });
        lines.push_str(&format!("{row}\n"));
    }
    let mut file = std::fs::OpenOptions::new().create(true).append(true).open(out)?;
    std::io::Write::write_all(&mut file, lines.as_bytes())?;
    println!("{}: {} tests", journal.display(), lines.lines().count());
    Ok(())
}
