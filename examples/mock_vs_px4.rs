//! How closely does the mock autopilot fly like real PX4? Flies every `test_*.yaml` of TESTS on an embedded
//! lockstep mock in `avoidance` mode (as `generate` does) and compares each flight with the report that
//! `prgenuav fly TEST --json` wrote for the same test on PX4 (`PX4_DIR/<test>.json`): minimum distance (MAE,
//! Spearman) and flight time (median ratio mock / PX4). Tests without a landed PX4 report are listed, not paired.
//!
//! `cargo run --release --example mock_vs_px4 -- TESTS PX4_DIR [PARALLEL=2]` (env `MOCK_PX4_DEFAULTS=1`: the mock
//! with PX4's own defaults instead of the campaign's mock profile; `MOCK_PROFILE=NAME`: that profile instead of the
//! default; `AGAINST=DIR`: no mock, the reports in DIR of the same tests flown again on PX4 in its place, which
//! measures how closely PX4 repeats itself: the best any model of it can do)

#[path = "common/mock_flight.rs"]
mod mock_flight;
#[path = "common/setting.rs"]
mod setting;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Context;
use mock_flight::{Flown, fly_mock};
use prgenuav::lfs::fidelity::aggregate;
use prgenuav::model::TestCase;
use tokio::sync::Semaphore;

fn px4_report(dir: &Path, name: &str) -> Option<Flown> {
    let text = std::fs::read_to_string(dir.join(format!("{name}.json"))).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    Some((
        v["status"].as_str()?.to_string(),
        v["min_distance"].as_f64(),
        v["flight_time_s"].as_f64()?,
    ))
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let (tests, px4) = match (args.next(), args.next()) {
        (Some(t), Some(p)) => (PathBuf::from(t), PathBuf::from(p)),
        _ => anyhow::bail!("usage: mock_vs_px4 TESTS PX4_DIR [PARALLEL]"),
    };
    let parallel: usize = args.next().map_or(Ok(2), |a| a.parse())?;
    let mut names: Vec<String> = std::fs::read_dir(&tests)
        .with_context(|| format!("reading {}", tests.display()))?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.starts_with("test_") && n.ends_with(".yaml"))
        .map(|n| n.trim_end_matches(".yaml").to_string())
        .collect();
    // test_7 before test_10; test_m4_2 before test_m4_10 before test_m5_0.
    names.sort_by_key(|n| {
        let (head, tail) = n.rsplit_once('_').unwrap_or((n.as_str(), ""));
        (head.to_string(), tail.parse::<u32>().unwrap_or(u32::MAX))
    });
    let rows = match std::env::var_os("AGAINST") {
        Some(again) => (names.iter())
            .map(|n| {
                let flown = px4_report(Path::new(&again), n).unwrap_or(("no report".into(), None, f64::NAN));
                (n.clone(), flown)
            })
            .collect(),
        None => fly_all(&tests, &names, parallel)?,
    };
    compare(&rows, &px4);
    Ok(())
}

/// Flies every named test on its own mock, `parallel` at a time.
fn fly_all(tests: &Path, names: &[String], parallel: usize) -> anyhow::Result<Vec<(String, Flown)>> {
    let rt = tokio::runtime::Runtime::new()?;
    let gate = Arc::new(Semaphore::new(parallel.max(1)));
    let rows = rt.block_on(async {
        let mut handles = Vec::new();
        for (seed, name) in (0u64..).zip(names) {
            let test = TestCase::load(&tests.join(format!("{name}.yaml")))?;
            let gate = gate.clone();
            handles.push(tokio::spawn(async move {
                let _permit = gate.acquire_owned().await?;
                fly_mock(test, seed).await
            }));
        }
        let mut rows = Vec::new();
        for (name, h) in names.iter().zip(handles) {
            rows.push((name.clone(), h.await??));
        }
        anyhow::Ok(rows)
    })?;
    Ok(rows)
}

/// Prints each test's two flights and the figures over the tests that landed on both.
fn compare(rows: &[(String, Flown)], px4: &Path) {
    let mut pairs = Vec::new();
    let mut ratios = Vec::new();
    println!("test\tmodel status\tmodel m\tmodel s\tpx4 status\tpx4 m\tpx4 s");
    for (name, (ms, md, mt)) in rows {
        let p = px4_report(px4, name);
        let show = |d: &Option<f64>| d.map_or("-".into(), |d| format!("{d:.2}"));
        match &p {
            Some((ps, pd, pt)) => println!("{name}\t{ms}\t{}\t{mt:.0}\t{ps}\t{}\t{pt:.0}", show(md), show(pd)),
            None => println!("{name}\t{ms}\t{}\t{mt:.0}\tno report", show(md)),
        }
        if let (Some(md), Some((ps, Some(pd), pt))) = (md, &p)
            && ms == "landed"
            && ps == "landed"
        {
            pairs.push((*md, *pd));
            ratios.push(mt / pt);
        }
    }
    ratios.sort_by(f64::total_cmp);
    let a = aggregate(&pairs);
    println!(
        "paired {} of {}: MAE {:.3} m, Spearman {:.3}, median flight-time ratio mock/PX4 {:.2}",
        a.n,
        rows.len(),
        a.mae.unwrap_or(f64::NAN),
        a.spearman.unwrap_or(f64::NAN),
        ratios.get(ratios.len() / 2).copied().unwrap_or(f64::NAN)
    );
}
