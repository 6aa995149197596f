//! How well does the low-fidelity simulator predict a flight? For N generated tests (missions 1-3 in turn,
//! generator seed 2026), compare the LFS-predicted minimum distance with the one flown against the mock
//! autopilot in `avoidance` mode through the bridge: mean absolute error, and how often both agree on
//! "below 1.5 m" (the competition's scoring threshold).
//!
//! `cargo run --release --example lfs_vs_mock -- [N=50] [SPEED=10] [PARALLEL=2]`

use std::path::Path;
use std::sync::Arc;

use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, fly, predict};
use prgenuav::generator::{Generator, GeneratorConfig};
use prgenuav::lfs::sim::MotionModel;
use prgenuav::model::TestCase;
use prgenuav::model::competition::FAIL_BELOW_M;
use tokio::sync::Semaphore;

#[derive(Debug, Clone)]
struct Row {
    test: String,
    lfs_paper: Option<f64>,
    lfs_px4: Option<f64>,
    flown: Option<f64>,
    status: String,
}

fn arg(i: usize, default: f64) -> f64 {
    std::env::args().nth(i).and_then(|a| a.parse().ok()).unwrap_or(default)
}

fn main() -> anyhow::Result<()> {
    let n = arg(1, 50.0) as usize;
    let speed = arg(2, 10.0);
    let parallel = arg(3, 2.0).max(1.0) as usize;
    let cases: Vec<TestCase> = (1..=3)
        .map(|m| TestCase::load(Path::new(&format!("missions/mission{m}.yaml"))))
        .collect::<Result<_, _>>()?;
    let mut tests = Vec::new();
    for i in 0..n {
        let case = &cases[i % 3];
        let g = Generator::new(case, GeneratorConfig::default(), 2026)?;
        let p = g.sample((i / 3) as u64)?;
        tests.push((
            format!("mission{}#{}", i % 3 + 1, i / 3),
            case.with_obstacles(p.obstacles.to_vec()),
        ));
    }
    let px4 = MotionModel::by_name("px4").expect("px4 model");
    let paper = MotionModel::by_name("paper").expect("paper model");
    let rt = tokio::runtime::Runtime::new()?;
    let gate = Arc::new(Semaphore::new(parallel));
    let rows: Vec<Row> = rt.block_on(async {
        let mut handles = Vec::new();
        for (name, test) in tests {
            let gate = gate.clone();
            handles.push(tokio::spawn(async move {
                let _permit = gate.acquire_owned().await.expect("semaphore");
                let lfs_px4 = predict(&test, px4, Default::default())
                    .ok()
                    .and_then(|p| p.min_distance);
                let lfs_paper = predict(&test, paper, Default::default())
                    .ok()
                    .and_then(|p| p.min_distance);
                let mock = MockAutopilot::builder()
                    .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
                    .speed_factor(SpeedFactor::Times(speed))
                    .spawn()
                    .await
                    .expect("mock");
                let port = mock.local_addr().expect("udp").port();
                let opts = FlyOptions {
                    connect: format!("udpout:127.0.0.1:{port}"),
                    mode: FlyMode::Avoidance,
                    time_scale: speed,
                    lfs_min_distance: lfs_px4,
                    ..FlyOptions::default()
                };
                let r = fly(&test, &opts, CancelToken::new()).await;
                let _ = mock.shutdown().await;
                let (flown, status) = match r {
                    Ok(r) => (r.min_distance, r.status.as_str().to_string()),
                    Err(e) => (None, format!("error: {e}")),
                };
                let row = Row {
                    test: name,
                    lfs_paper,
                    lfs_px4,
                    flown,
                    status,
                };
                eprintln!("{row:?}");
                row
            }));
        }
        let mut rows = Vec::new();
        for h in handles {
            rows.push(h.await.expect("task"));
        }
        rows
    });
    println!("test,lfs_paper_m,lfs_px4_m,flown_m,status");
    let f = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.3}"));
    for r in &rows {
        println!(
            "{},{},{},{},{}",
            r.test,
            f(r.lfs_paper),
            f(r.lfs_px4),
            f(r.flown),
            r.status
        );
    }
    for (model, pick) in [("px4", 0), ("paper", 1)] {
        let pairs: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| {
                let lfs = if pick == 0 { r.lfs_px4 } else { r.lfs_paper };
                Some((lfs?, r.flown?))
            })
            .collect();
        let k = pairs.len() as f64;
        let mae = pairs.iter().map(|(a, b)| (a - b).abs()).sum::<f64>() / k;
        let agree = pairs
            .iter()
            .filter(|(a, b)| (*a < FAIL_BELOW_M) == (*b < FAIL_BELOW_M))
            .count();
        let below_flown = pairs.iter().filter(|(_, b)| *b < FAIL_BELOW_M).count();
        let below_lfs = pairs.iter().filter(|(a, _)| *a < FAIL_BELOW_M).count();
        println!(
            "# LFS {model} motion vs mock-flown ({} of {} tests): MAE {mae:.3} m; agree on < {FAIL_BELOW_M} m in {agree}/{} \
             ({:.0} %); below {FAIL_BELOW_M} m: LFS {below_lfs}, flown {below_flown}",
            pairs.len(),
            rows.len(),
            pairs.len(),
            100.0 * agree as f64 / k
        );
    }
    let statuses = rows.iter().fold(std::collections::BTreeMap::new(), |mut m, r| {
        *m.entry(r.status.clone()).or_insert(0) += 1;
        m
    });
    println!("# flown statuses: {statuses:?}");
    Ok(())
}
