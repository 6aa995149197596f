//! Fits the mock's gusts (`MOCK_GUST_ACC`, the stand-in for PX4's flight-to-flight scatter) to how much real
//! PX4 v1.14 SIH disagrees with itself when it flies the same test twice.
//!
//! The PX4 pairs: the 42 held-out tests on missions 4-7 flown twice (`tests/data/px4-heldout`, `px4` and
//! `px4-again`, neither chosen by its outcome), and the campaign tests flown three times or more
//! (`tests/data/px4-campaign-draws`: their second and third flights, both made because the first failed, so
//! neither is chosen by its own outcome). Each test is flown twice on a fresh lockstep mock with the campaign's
//! mock profile plus the gusts, each flight with its own seed.
//!
//! `cargo run --release --example mock_scatter -- fly OUT RMS [TAU=1] [PARALLEL=2]` appends one gust setting's
//! flights to `OUT/scatter.csv` (a setting already there is skipped; about 4 minutes on 2 cores).
//! `cargo run --release --example mock_scatter -- cv OUT` prints, per setting, the median and mean |d1 - d2|
//! of the mock's pairs against PX4's, then the cross-validated choice: folds by campaign (and by mission for
//! the held-out tests), each fold's pairs predicted by the setting whose median |d1 - d2| is nearest PX4's on
//! the other folds.

// The shared module's env-driven `fly_mock` is for the other examples; this one flies its own settings.
#[path = "common/csv_append.rs"]
mod csv_append;
#[allow(dead_code)]
#[path = "common/mock_flight.rs"]
mod mock_flight;
#[path = "common/setting.rs"]
mod setting;

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;
use std::sync::Arc;

use anyhow::Context;
use prgenuav::bridge::{FlyMode, FlyOptions};
use prgenuav::campaign::fly::mock_mavlink::mock_builder_with;
use prgenuav::model::{Obstacle, TestCase};
use serde::Deserialize;
use tokio::sync::Semaphore;

const DRAWS: &str = "tests/data/px4-campaign-draws/tests.jsonl";
const HELDOUT: &str = "tests/data/px4-heldout";
const HEADER: &str = "setting,fold,id,px4_a,px4_b,mock_a,mock_b";

/// A test PX4 flew twice: its fold, a name, the test and the two PX4 distances (m).
struct Pair {
    fold: String,
    id: String,
    test: TestCase,
    px4: (f64, f64),
}

#[derive(Deserialize)]
struct DrawRow {
    mission: u32,
    campaign: String,
    candidate: u64,
    obstacles: Vec<Obstacle>,
    px4_min_distance: Vec<Option<f64>>,
    px4_status: Vec<String>,
}

#[derive(Deserialize)]
struct Report {
    status: String,
    min_distance: Option<f64>,
}

fn landed(path: &Path) -> Option<f64> {
    let r: Report = serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()?;
    r.min_distance.filter(|_| r.status == "landed")
}

fn pairs() -> anyhow::Result<Vec<Pair>> {
    let mut out = Vec::new();
    let text = std::fs::read_to_string(DRAWS).with_context(|| format!("reading {DRAWS}"))?;
    for (i, line) in text.lines().enumerate() {
        let row: DrawRow = serde_json::from_str(line).with_context(|| format!("{DRAWS}:{}", i + 1))?;
        let d: Vec<f64> = (row.px4_min_distance.iter().zip(&row.px4_status))
            .filter_map(|(d, s)| d.filter(|_| s == "landed"))
            .collect();
        if d.len() >= 3 {
            let base = TestCase::load(Path::new(&format!("missions/mission{}.yaml", row.mission)))?;
            out.push(Pair {
                id: format!("{}#{}", row.campaign, row.candidate),
                fold: row.campaign,
                test: base.with_obstacles(row.obstacles),
                px4: (d[1], d[2]),
            });
        }
    }
    let dir = Path::new(HELDOUT);
    let mut names: Vec<String> = std::fs::read_dir(dir.join("tests"))?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| n.strip_suffix(".yaml").map(str::to_string))
        .collect();
    names.sort();
    for name in names {
        let json = format!("{name}.json");
        if let (Some(a), Some(b)) = (
            landed(&dir.join("px4").join(&json)),
            landed(&dir.join("px4-again").join(&json)),
        ) {
            let mission = name.split('_').nth(1).unwrap_or("m?").to_string();
            out.push(Pair {
                fold: format!("heldout-{mission}"),
                test: TestCase::load(&dir.join("tests").join(format!("{name}.yaml")))?,
                id: name,
                px4: (a, b),
            });
        }
    }
    Ok(out)
}

/// One mock flight of `test` with `setting`'s gusts from `seed`: its distance if it landed.
async fn fly_once(test: &TestCase, setting: &str, seed: u64) -> anyhow::Result<Option<f64>> {
    let profile = setting::parse_setting(setting)?;
    let builder = mock_builder_with(&profile, FlyMode::Avoidance).seed(seed);
    let r = mock_flight::fly_on_mock(test, builder, FlyOptions::default()).await?;
    Ok(r.min_distance.filter(|_| r.status.as_str() == "landed"))
}

/// One test's row: its fold, PX4's two distances and the mock's two (m).
type FlownPair = (String, f64, f64, f64, f64);

fn read_rows(out: &Path) -> BTreeMap<String, Vec<FlownPair>> {
    let mut by: BTreeMap<String, Vec<FlownPair>> = BTreeMap::new();
    let text = std::fs::read_to_string(out.join("scatter.csv")).unwrap_or_default();
    for line in text.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |i: usize| f.get(i).and_then(|x| x.parse::<f64>().ok());
        if let (Some(a), Some(b), Some(c), Some(d)) = (num(3), num(4), num(5), num(6)) {
            by.entry(f[0].to_string())
                .or_default()
                .push((f[1].to_string(), a, b, c, d));
        }
    }
    by
}

fn fly_setting(out: &Path, rms: f64, tau: f64, parallel: usize) -> anyhow::Result<()> {
    let name = format!("gust{rms}_tau{tau}");
    if read_rows(out).contains_key(&name) {
        eprintln!("{name}: already flown");
        return Ok(());
    }
    let setting = format!("MOCK_GUST_ACC={rms},MOCK_GUST_TAU={tau}");
    let rt = tokio::runtime::Runtime::new()?;
    let gate = Arc::new(Semaphore::new(parallel.max(1)));
    let rows = rt.block_on(async {
        let mut handles = Vec::new();
        for (k, pair) in (0u64..).zip(pairs()?) {
            let (gate, setting) = (gate.clone(), setting.clone());
            handles.push(tokio::spawn(async move {
                let _permit = gate.acquire_owned().await?;
                let a = fly_once(&pair.test, &setting, 2 * k).await?;
                let b = fly_once(&pair.test, &setting, 2 * k + 1).await?;
                anyhow::Ok((pair, a, b))
            }));
        }
        let mut rows = Vec::new();
        for h in handles {
            rows.push(h.await??);
        }
        anyhow::Ok(rows)
    })?;
    let mut f = csv_append::append_csv(out, "scatter.csv", HEADER)?;
    let show = |d: Option<f64>| d.map_or(String::new(), |d| format!("{d:.4}"));
    for (p, a, b) in rows {
        let (pa, pb) = p.px4;
        writeln!(f, "{name},{},{},{pa:.4},{pb:.4},{},{}", p.fold, p.id, show(a), show(b))?;
    }
    Ok(())
}

/// (median, mean) of |a - b| over `pairs`.
fn spread(pairs: &[(f64, f64)]) -> (f64, f64) {
    let mut d: Vec<f64> = pairs.iter().map(|(a, b)| (a - b).abs()).collect();
    d.sort_by(f64::total_cmp);
    let median = d.get(d.len() / 2).copied().unwrap_or(f64::NAN);
    (median, d.iter().sum::<f64>() / d.len().max(1) as f64)
}

fn cv(out: &Path) -> anyhow::Result<()> {
    let rows = read_rows(out);
    anyhow::ensure!(!rows.is_empty(), "no flights in {}", out.join("scatter.csv").display());
    println!("| setting | pairs | median abs(d1 - d2): mock / PX4 | mean: mock / PX4 |");
    println!("|---|---|---|---|");
    for (name, r) in &rows {
        let (mm, mmean) = spread(&r.iter().map(|x| (x.3, x.4)).collect::<Vec<_>>());
        let (pm, pmean) = spread(&r.iter().map(|x| (x.1, x.2)).collect::<Vec<_>>());
        println!("| {name} | {} | {mm:.3} / {pm:.3} | {mmean:.3} / {pmean:.3} |", r.len());
    }
    let folds: std::collections::BTreeSet<&str> = rows.values().flatten().map(|x| x.0.as_str()).collect();
    println!("\n| fold | pairs | chosen on the other folds | median abs(d1 - d2): mock / PX4 |");
    println!("|---|---|---|---|");
    let (mut mock_all, mut px4_all) = (Vec::new(), Vec::new());
    for fold in folds {
        let gap = |name: &String| {
            let r: Vec<_> = rows[name].iter().filter(|x| x.0 != fold).collect();
            let m = spread(&r.iter().map(|x| (x.3, x.4)).collect::<Vec<_>>()).0;
            let p = spread(&r.iter().map(|x| (x.1, x.2)).collect::<Vec<_>>()).0;
            (m - p).abs()
        };
        let chosen = rows
            .keys()
            .min_by(|a, b| gap(a).total_cmp(&gap(b)))
            .context("no setting")?;
        let held: Vec<_> = rows[chosen].iter().filter(|x| x.0 == fold).collect();
        let mock: Vec<(f64, f64)> = held.iter().map(|x| (x.3, x.4)).collect();
        let px4: Vec<(f64, f64)> = held.iter().map(|x| (x.1, x.2)).collect();
        println!(
            "| {fold} | {} | {chosen} | {:.3} / {:.3} |",
            held.len(),
            spread(&mock).0,
            spread(&px4).0
        );
        mock_all.extend(mock);
        px4_all.extend(px4);
    }
    let (mm, mmean) = spread(&mock_all);
    let (pm, pmean) = spread(&px4_all);
    println!(
        "| **all, out of fold** | {} | | **{mm:.3} / {pm:.3}** (mean {mmean:.3} / {pmean:.3}) |",
        mock_all.len()
    );
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize| args.get(i).map(String::as_str);
    match (arg(0), arg(1)) {
        (Some("fly"), Some(out)) => {
            let rms: f64 = arg(2).context("fly OUT RMS [TAU] [PARALLEL]")?.parse()?;
            let tau: f64 = arg(3).map_or(Ok(1.0), str::parse)?;
            let parallel: usize = arg(4).map_or(Ok(2), str::parse)?;
            fly_setting(Path::new(out), rms, tau, parallel)
        }
        (Some("cv"), Some(out)) => cv(Path::new(out)),
        _ => anyhow::bail!("usage: mock_scatter fly OUT RMS [TAU=1] [PARALLEL=2] | mock_scatter cv OUT"),
    }
}
