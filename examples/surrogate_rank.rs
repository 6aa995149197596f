//! Does anything we can run order a suite's tests as PX4 does? Reads the 59 written tests of six PX4 v1.14
//! SIH campaigns, each flown 10 times by `evaluate` (`tests/data/px4-repeated/tests.jsonl`), and ranks their
//! 10-flight means by:
//! - PX4 itself, one 5-flight evaluation against the other (the judge's repeatability: what any predictor
//!   is capped by);
//! - the LFS, one prediction each with the `px4` motion model (as `generate` screens) and the `paper` one;
//! - the embedded mock with the campaign's profile, `MOCK_RUNS` flights each (default 10; 0 skips it).
//!
//! Prints, per mission and overall, the Spearman of each against PX4's mean distance and mean points; then,
//! per mission, what any 10 of these tests (distinct boxes) could score: the best 10 by their own 10-flight
//! test scores (hindsight, no similarity penalty); the best 10 by one evaluation's 5 flights, scored by the
//! other's (what picking by PX4's own flights earns at the next evaluation); and the ceiling of 10 tests
//! that earn 1 point on every flight at the 10 shortest mean flight times (2 points need a flight below
//! 1 m: their count is printed too). Last, each suite's total in either evaluation against the spread its
//! runs' scatter predicts for the difference.
//!
//! `cargo run --release --example surrogate_rank -- [PARALLEL=2]` (about 5 minutes on 2 cores with the mock;
//! `MOCK_RUNS=0`: the LFS alone, seconds; `MOCK_PROFILE=NAME` or `MOCK_SETTING=...` as in `mock_fit`).

#[path = "common/mock_flight.rs"]
mod mock_flight;
#[path = "common/setting.rs"]
mod setting;

use std::path::Path;
use std::sync::Arc;

use anyhow::Context;
use prgenuav::bridge::predict;
use prgenuav::judge::{points, test_score, test_score_sd};
use prgenuav::lfs::fidelity::spearman;
use prgenuav::lfs::sim::MotionModel;
use prgenuav::model::competition::TEST_SCORE_SCALE;
use prgenuav::model::{Obstacle, TestCase};
use serde::Deserialize;
use tokio::sync::Semaphore;

const DATA: &str = "tests/data/px4-repeated/tests.jsonl";

/// One test and its PX4 flights.
#[derive(Debug, Clone, Deserialize)]
struct Row {
    mission: u32,
    suite: String,
    obstacles: Vec<Obstacle>,
    /// Every PX4 flight, metres (the 2026 judge), in flight order.
    px4_min_distance: Vec<f64>,
    /// Their flight times, seconds.
    px4_flight_time_s: Vec<f64>,
    /// Which of the two evaluations flew each flight (1 or 2).
    evaluation: Vec<u8>,
}

/// A figure per test: PX4's and the predictors' (NaN where a predictor has none).
struct Figures {
    mission: u32,
    /// The 2026 test score of the 10 flights.
    px4_score: f64,
    px4_minutes: f64,
    below_1m: usize,
    obstacles: usize,
    px4_distance: f64,
    px4_points: f64,
    first_half: (f64, f64),
    second_half: (f64, f64),
    suite: String,
    /// The 2026 test score of each evaluation's 5 flights alone.
    half_scores: (f64, f64),
    /// The variance of each of those scores that the runs' own scatter predicts.
    half_variances: (f64, f64),
    /// The boxes, as text: one test may stand in two suites.
    boxes: String,
    lfs_px4: f64,
    lfs_paper: f64,
    mock: (f64, f64),
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// (mean distance, mean points) of `d`.
fn judged(d: &[f64]) -> (f64, f64) {
    let p: Vec<f64> = d.iter().map(|x| f64::from(points(*x))).collect();
    (mean(d), mean(&p))
}

/// One evaluation's flights: (distances, flight times).
fn flights_of(row: &Row, k: u8) -> (Vec<f64>, Vec<f64>) {
    (row.px4_min_distance
        .iter()
        .zip(&row.px4_flight_time_s)
        .zip(&row.evaluation))
    .filter(|(_, e)| **e == k)
    .map(|((d, t), _)| (*d, *t))
    .unzip()
}

fn half(row: &Row, k: u8) -> (f64, f64) {
    judged(&flights_of(row, k).0)
}

fn half_score(row: &Row, k: u8) -> f64 {
    let (d, t) = flights_of(row, k);
    test_score(&d, &t, row.obstacles.len())
}

/// The variance of [`half_score`] from the runs' own scatter.
fn half_variance(row: &Row, k: u8) -> f64 {
    let (d, t) = flights_of(row, k);
    test_score_sd(&d, &t, row.obstacles.len()).map_or(f64::NAN, |sd| sd * sd)
}

async fn figures(row: Row, seed: u64, mock_runs: u64) -> anyhow::Result<Figures> {
    let case = TestCase::load(Path::new(&format!("missions/mission{}.yaml", row.mission)))?;
    let test = case.with_obstacles(row.obstacles.clone());
    let lfs = |name: &str| -> anyhow::Result<f64> {
        let motion = MotionModel::by_name(name).with_context(|| format!("the {name} motion model"))?;
        let p = predict(&test, motion, Default::default()).map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(p.min_distance.unwrap_or(f64::NAN))
    };
    let (lfs_px4, lfs_paper) = (lfs("px4")?, lfs("paper")?);
    let mut flown = Vec::new();
    for k in 0..mock_runs {
        let (status, d, _) = mock_flight::fly_mock(test.clone(), seed * 1000 + k).await?;
        flown.extend(d.filter(|_| status == "landed"));
    }
    let (px4_distance, px4_points) = judged(&row.px4_min_distance);
    Ok(Figures {
        mission: row.mission,
        px4_score: test_score(&row.px4_min_distance, &row.px4_flight_time_s, row.obstacles.len()),
        px4_minutes: mean(&row.px4_flight_time_s) / 60.0,
        below_1m: row.px4_min_distance.iter().filter(|d| **d < 1.0).count(),
        obstacles: row.obstacles.len(),
        px4_distance,
        px4_points,
        first_half: half(&row, 1),
        second_half: half(&row, 2),
        suite: row.suite.clone(),
        half_scores: (half_score(&row, 1), half_score(&row, 2)),
        half_variances: (half_variance(&row, 1), half_variance(&row, 2)),
        boxes: serde_json::to_string(&row.obstacles)?,
        lfs_px4,
        lfs_paper,
        mock: judged(&flown),
    })
}

/// Spearman over the tests where both figures are numbers.
fn rho(fs: &[&Figures], a: impl Fn(&Figures) -> f64, b: impl Fn(&Figures) -> f64) -> String {
    let (x, y): (Vec<f64>, Vec<f64>) = (fs.iter())
        .map(|f| (a(f), b(f)))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .unzip();
    spearman(&x, &y).map_or("-".into(), |r| format!("{r:.2}"))
}

fn main() -> anyhow::Result<()> {
    let parallel: usize = std::env::args().nth(1).map_or(Ok(2), |a| a.parse())?;
    let mock_runs: u64 = std::env::var("MOCK_RUNS").map_or(Ok(10), |v| v.parse())?;
    let text = std::fs::read_to_string(DATA).with_context(|| format!("reading {DATA}"))?;
    let rows: Vec<Row> = (text.lines().enumerate())
        .map(|(i, l)| serde_json::from_str(l).with_context(|| format!("{DATA}:{}", i + 1)))
        .collect::<anyhow::Result<_>>()?;
    let rt = tokio::runtime::Runtime::new()?;
    let gate = Arc::new(Semaphore::new(parallel.max(1)));
    let all = rt.block_on(async {
        let mut handles = Vec::new();
        for (seed, row) in (0u64..).zip(rows) {
            let gate = gate.clone();
            handles.push(tokio::spawn(async move {
                let _permit = gate.acquire_owned().await?;
                figures(row, seed, mock_runs).await
            }));
        }
        let mut out = Vec::new();
        for h in handles {
            out.push(h.await??);
        }
        anyhow::Ok(out)
    })?;
    println!(
        "| tests | PX4 evaluation 1 vs 2: distance / points | LFS px4 / paper vs PX4 distance | mock ({mock_runs} \
         flights) vs PX4: distance / points |"
    );
    println!("|---|---|---|---|");
    for mission in [Some(2), Some(5), None] {
        let fs: Vec<&Figures> = all.iter().filter(|f| mission.is_none_or(|m| f.mission == m)).collect();
        let label = mission.map_or("all".to_string(), |m| format!("mission {m}"));
        println!(
            "| {label}: {} | {} / {} | {} / {} | {} / {} |",
            fs.len(),
            rho(&fs, |f| f.first_half.0, |f| f.second_half.0),
            rho(&fs, |f| f.first_half.1, |f| f.second_half.1),
            rho(&fs, |f| f.lfs_px4, |f| f.px4_distance),
            rho(&fs, |f| f.lfs_paper, |f| f.px4_distance),
            rho(&fs, |f| f.mock.0, |f| f.px4_distance),
            rho(&fs, |f| f.mock.1, |f| f.px4_points),
        );
    }
    println!(
        "\n| mission | distinct tests | flights below 1 m | best 10 in hindsight: total (mean points) | best 10 of \
         one evaluation, scored by the other (1 on 2 / 2 on 1) | 10 tests at 1 point a flight |"
    );
    println!("|---|---|---|---|---|---|");
    for mission in [2, 5] {
        let fs = distinct(all.iter().filter(|f| f.mission == mission).collect());
        println!(
            "| {mission} | {} | {} of {} | {} | {:.2} / {:.2} | {:.2} |",
            fs.len(),
            fs.iter().map(|f| f.below_1m).sum::<usize>(),
            fs.len() * 10,
            hindsight(&fs),
            picked_by(&fs, |f| f.half_scores.0, |f| f.half_scores.1),
            picked_by(&fs, |f| f.half_scores.1, |f| f.half_scores.0),
            one_point_ceiling(&fs)
        );
    }
    repeat_table(&all);
    Ok(())
}

/// Each suite's total in either evaluation, against the spread its runs' own scatter predicts for the
/// difference (z = difference / that spread).
fn repeat_table(all: &[Figures]) {
    println!("\n| suite | evaluation 1 | evaluation 2 | difference | spread the runs predict (sd) | z |");
    println!("|---|---|---|---|---|---|");
    let mut suites: Vec<&str> = all.iter().map(|f| f.suite.as_str()).collect();
    suites.sort_unstable();
    suites.dedup();
    for suite in suites {
        let fs: Vec<&Figures> = all.iter().filter(|f| f.suite == suite).collect();
        let sum = |g: fn(&Figures) -> f64| fs.iter().map(|f| g(f)).sum::<f64>();
        let (a, b) = (sum(|f| f.half_scores.0), sum(|f| f.half_scores.1));
        let sd = (sum(|f| f.half_variances.0) + sum(|f| f.half_variances.1)).sqrt();
        println!(
            "| {suite} | {a:.2} | {b:.2} | {:+.2} | {sd:.2} | {:+.1} |",
            b - a,
            (b - a) / sd
        );
    }
}

/// The tests with distinct boxes, the first of each kept: a test two suites share is one test to pick.
fn distinct(fs: Vec<&Figures>) -> Vec<&Figures> {
    let mut seen = std::collections::HashSet::new();
    fs.into_iter().filter(|f| seen.insert(f.boxes.as_str())).collect()
}

/// The 10 best tests' total score and their summed mean points.
fn hindsight(fs: &[&Figures]) -> String {
    let best = best_10(fs, |f| f.px4_score);
    let total: f64 = best.iter().map(|f| f.px4_score).sum();
    let points: f64 = best.iter().map(|f| f.px4_points).sum();
    format!("{total:.2} ({points:.1})")
}

/// The total `scored` gives the 10 best tests by `picked`: a selection by 5 PX4 flights a test, judged on
/// 5 others, as a campaign that had flown every test 5 times would be judged.
fn picked_by(fs: &[&Figures], picked: impl Fn(&Figures) -> f64, scored: impl Fn(&Figures) -> f64) -> f64 {
    best_10(fs, picked).iter().map(|f| scored(f)).sum()
}

fn best_10<'a>(fs: &[&'a Figures], by: impl Fn(&Figures) -> f64) -> Vec<&'a Figures> {
    let mut sorted: Vec<&Figures> = fs.to_vec();
    sorted.sort_by(|a, b| by(b).total_cmp(&by(a)));
    sorted.truncate(10);
    sorted
}

/// The total of 10 tests earning 1 point on every flight, at the 10 shortest mean flight times.
fn one_point_ceiling(fs: &[&Figures]) -> f64 {
    let mut each: Vec<f64> = (fs.iter())
        .map(|f| TEST_SCORE_SCALE / ((f.obstacles * f.obstacles) as f64 * f.px4_minutes))
        .collect();
    each.sort_by(|a, b| b.total_cmp(a));
    each.iter().take(10).sum()
}
