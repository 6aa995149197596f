//! Recorded vs PX4 vs LFS vs mock: the tables of README's *Real PX4 as a second reference*. Reads the recorded
//! cases (DIR), the PX4 reference (PX4_DIR, written by `examples/px4_reference.rs`) and optionally the mock's
//! distances (MOCK_CSV: `id,real_m,mock_m`, the output of `examples/mock_fidelity.rs`), simulates the LFS
//! (`paper` and `px4` motion) and prints, overall and per tier: each source against the recorded flights and
//! against PX4 (MAE, Spearman, precision / recall of "< 1.5 m", mean signed error, ROC AUC of its failures; a PX4 flight that did not land is no truth), the split of the LFS's
//! squared error into LFS-vs-PX4 and PX4-vs-recorded, the recorded simulator's own repeat noise, and the
//! horizontal speeds flown (tier A, the only recorded trajectories); then the prequential cross-validation of
//! the online calibration's prior weight (`campaign::learn::calibration`): for each truth (recorded, PX4) the flights in
//! 50 random orders of obstacle sets, each predicted by the LFS (`px4` motion) plus the bias learnt from the
//! flights before it, mean absolute error over the first 25 flights (a campaign's early quarter) and all.
//!
//! Last, the competition bench's targets on tiers A and B: median absolute and signed error, Spearman, the
//! share with the recorded verdict (below 1.5 m or not) and the median ratio of flight times (PX4's over the
//! recorded `duration_s`).
//!
//! `cargo run --release --example px4_compare -- [DIR=tests/data/hfs-flights] [PX4_DIR=tests/data/px4-flights]
//! [MOCK_CSV]`

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use prgenuav::campaign::learn::calibration::{Calibration, prequential_errors};
use prgenuav::lfs::eval::calibration::roc_auc;
use prgenuav::lfs::fidelity::{FlightCase, aggregate, evaluate, load_dir};
use prgenuav::lfs::px4_flights;
use prgenuav::lfs::sim::{MotionModel, SimConfig};
use prgenuav::model::Trajectory;
use prgenuav::model::competition::FAIL_BELOW_M;

/// Per case: recorded, PX4, LFS paper, LFS px4, mock.
#[derive(Debug, Clone)]
struct Row {
    id: String,
    tier: String,
    group: Option<String>,
    real: f64,
    px4: Option<f64>,
    paper: Option<f64>,
    lfs_px4: Option<f64>,
    mock: Option<f64>,
}

fn line(name: &str, rows: &[&Row], pred: impl Fn(&Row) -> Option<f64>, truth: impl Fn(&Row) -> Option<f64>) {
    let pairs: Vec<(f64, f64)> = rows.iter().filter_map(|r| Some((pred(r)?, truth(r)?))).collect();
    let a = aggregate(&pairs);
    let bias = (!pairs.is_empty()).then(|| pairs.iter().map(|(p, t)| p - t).sum::<f64>() / pairs.len() as f64);
    let f = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3}"));
    // How well the prediction separates the truth's failures: the closer predicted, the likelier failing.
    let scores: Vec<f64> = pairs.iter().map(|(p, _)| -p).collect();
    let failed: Vec<bool> = pairs.iter().map(|(_, t)| *t < FAIL_BELOW_M).collect();
    println!(
        "| {name} | {} | {} | {} | {} | {} | {} | {} |",
        a.n,
        f(a.mae),
        f(a.spearman),
        f(a.precision),
        f(a.recall),
        f(bias),
        f(roc_auc(&scores, &failed))
    );
}

/// Mean squared error and its split e = (lfs - px4) + (px4 - real).
fn split(rows: &[&Row], lfs: impl Fn(&Row) -> Option<f64>) {
    let t: Vec<(f64, f64, f64)> = rows.iter().filter_map(|r| Some((lfs(r)?, r.px4?, r.real))).collect();
    let n = t.len() as f64;
    if t.is_empty() {
        return;
    }
    let mse = |f: &dyn Fn(&(f64, f64, f64)) -> f64| t.iter().map(|x| f(x).powi(2)).sum::<f64>() / n;
    let total = mse(&|(l, _, r)| l - r);
    let model = mse(&|(l, p, _)| l - p);
    let stack = mse(&|(_, p, r)| p - r);
    let cross = t.iter().map(|(l, p, r)| 2.0 * (l - p) * (p - r)).sum::<f64>() / n;
    println!(
        "n {} | MSE(LFS - recorded) {total:.3} = MSE(LFS - PX4) {model:.3} + MSE(PX4 - recorded) {stack:.3} + 2 cov {cross:.3}",
        t.len()
    );
}

/// 95th percentile and mean of the horizontal speed from 1 s central differences of a 0.5 s series.
fn speeds(samples: &[(f64, f64, f64)]) -> Option<(f64, f64)> {
    let mut v: Vec<f64> = samples
        .windows(3)
        .filter(|w| w[2].0 > w[0].0)
        .map(|w| (w[2].1 - w[0].1).hypot(w[2].2 - w[0].2) / (w[2].0 - w[0].0))
        .filter(|s| *s > 0.2)
        .collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let p95 = v[((v.len() - 1) as f64 * 0.95).round() as usize];
    Some((p95, v.iter().sum::<f64>() / v.len() as f64))
}

fn recorded_samples(dir: &Path, id: &str) -> Option<Vec<(f64, f64, f64)>> {
    let text = std::fs::read_to_string(dir.join(format!("{id}.json"))).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    v["trajectory"]
        .as_array()?
        .iter()
        .map(|s| Some((s[0].as_f64()?, s[1].as_f64()?, s[2].as_f64()?)))
        .collect()
}

/// The competition bench's targets on tiers A and B (recorded duration from each case's `duration_s`).
fn bench_targets(rows: &[Row], px4: &BTreeMap<String, px4_flights::Px4Flight>, dir: &Path) {
    let ab: Vec<&Row> = rows.iter().filter(|r| r.tier == "A" || r.tier == "B").collect();
    let pairs: Vec<(f64, f64)> = ab.iter().filter_map(|r| Some((r.px4?, r.real))).collect();
    if pairs.is_empty() {
        return;
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let abs = median(pairs.iter().map(|(p, t)| (p - t).abs()).collect());
    let signed = median(pairs.iter().map(|(p, t)| p - t).collect());
    let same = pairs.iter().filter(|(p, t)| (*p < 1.5) == (*t < 1.5)).count();
    let spearman = aggregate(&pairs).spearman.map_or("-".into(), |s| format!("{s:.3}"));
    let ratios: Vec<f64> = ab
        .iter()
        .filter_map(|r| {
            let flown = px4.get(&r.id)?.flight_time_s;
            let text = std::fs::read_to_string(dir.join(format!("{}.json", r.id))).ok()?;
            let recorded = serde_json::from_str::<serde_json::Value>(&text).ok()?["duration_s"].as_f64()?;
            (recorded > 0.0 && flown > 0.0).then_some(flown / recorded)
        })
        .collect();
    let ratio = if ratios.is_empty() {
        "-".into()
    } else {
        format!("{:.2} ({} flights)", median(ratios.clone()), ratios.len())
    };
    println!(
        "\n### bench targets, tiers A and B\n\n| n | median abs error | median signed error | Spearman | same verdict | flight time ratio (median) |\n|---|---|---|---|---|---|\n| {} | {abs:.3} m | {signed:+.3} m | {spearman} | {} of {} ({:.0} %) | {ratio} |",
        pairs.len(),
        same,
        pairs.len(),
        100.0 * same as f64 / pairs.len() as f64
    );
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().unwrap_or_else(|| "tests/data/hfs-flights".into()));
    let px4_dir = PathBuf::from(args.next().unwrap_or_else(|| "tests/data/px4-flights".into()));
    let mock_csv = args.next().map(PathBuf::from);
    let (cases, _) = load_dir(&dir)?;
    let cases: Vec<FlightCase> = cases.into_iter().filter(|c| !c.obstacles.is_empty()).collect();
    let px4: BTreeMap<String, px4_flights::Px4Flight> = px4_flights::load(&px4_dir, &cases)?
        .into_iter()
        .map(|f| (f.id.clone(), f))
        .collect();
    let mut mock: BTreeMap<String, f64> = BTreeMap::new();
    if let Some(p) = &mock_csv {
        for l in std::fs::read_to_string(p)?.lines().skip(1) {
            let f: Vec<&str> = l.split(',').collect();
            if let (Some(id), Some(Ok(d))) = (f.first(), f.get(2).map(|s| s.parse::<f64>())) {
                mock.insert(id.to_string(), d);
            }
        }
    }
    let jobs = std::thread::available_parallelism().map_or(1, |j| j.get());
    let sim = |m: &str| -> anyhow::Result<BTreeMap<String, Option<f64>>> {
        let motion = MotionModel::by_name(m).ok_or_else(|| anyhow::anyhow!("motion {m}"))?;
        let config = SimConfig {
            motion,
            ..SimConfig::default()
        };
        Ok(evaluate(&cases, Vec::new(), &config, jobs)
            .cases
            .into_iter()
            .map(|c| (c.id, c.predicted))
            .collect())
    };
    let (paper, lfs_px4) = (sim("paper")?, sim("px4")?);
    let rows: Vec<Row> = cases
        .iter()
        .map(|c| Row {
            id: c.id.clone(),
            tier: c.tier.clone(),
            group: c.repeat_group.clone(),
            real: c.real_m,
            // A flight that did not land has no judged distance: never a truth.
            px4: px4
                .get(&c.id)
                .filter(|f| f.status == "landed")
                .and_then(|f| f.min_distance),
            paper: paper.get(&c.id).copied().flatten(),
            lfs_px4: lfs_px4.get(&c.id).copied().flatten(),
            mock: mock.get(&c.id).copied(),
        })
        .collect();
    let not_landed: Vec<String> = px4
        .values()
        .filter(|f| f.status != "landed")
        .map(|f| format!("{} {}", f.id, f.status))
        .collect();
    println!(
        "PX4 flights: {} of {} cases; not landed: {not_landed:?}",
        px4.len(),
        cases.len()
    );
    let mut tiers: Vec<(String, Vec<&Row>)> = vec![("all".into(), rows.iter().collect())];
    for t in ["A", "B", "C"] {
        tiers.push((t.into(), rows.iter().filter(|r| r.tier == t).collect()));
    }
    for (tier, rs) in &tiers {
        println!(
            "\n### tier {tier}\n\n| prediction vs truth | n | MAE | Spearman | precision | recall | mean signed error | ROC AUC |"
        );
        println!("|---|---|---|---|---|---|---|---|");
        let real = |r: &Row| Some(r.real);
        line("PX4 vs recorded", rs, |r| r.px4, real);
        line("LFS paper vs recorded", rs, |r| r.paper, real);
        line("LFS px4 vs recorded", rs, |r| r.lfs_px4, real);
        line("mock vs recorded", rs, |r| r.mock, real);
        line("LFS paper vs PX4", rs, |r| r.paper, |r| r.px4);
        line("LFS px4 vs PX4", rs, |r| r.lfs_px4, |r| r.px4);
        line("mock vs PX4", rs, |r| r.mock, |r| r.px4);
        print!("\nLFS paper: ");
        split(rs, |r| r.paper);
        print!("LFS px4: ");
        split(rs, |r| r.lfs_px4);
    }
    bench_targets(&rows, &px4, &dir);
    // The recorded simulator's own noise: spread of repeats of one obstacle set.
    let mut groups: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for r in &rows {
        if let Some(g) = &r.group {
            groups.entry(g).or_default().push(r.real);
        }
    }
    let (mut dev, mut sq, mut n) = (0.0, 0.0, 0usize);
    for v in groups.values().filter(|v| v.len() > 1) {
        let mut s = v.clone();
        s.sort_by(f64::total_cmp);
        let med = s[s.len() / 2];
        let mean = s.iter().sum::<f64>() / s.len() as f64;
        dev += s.iter().map(|x| (x - med).abs()).sum::<f64>();
        sq += s.iter().map(|x| (x - mean).powi(2)).sum::<f64>() * s.len() as f64 / (s.len() - 1) as f64;
        n += s.len();
    }
    if n > 0 {
        println!(
            "\nrecorded repeat noise: {} flights in {} groups: mean |d - group median| {:.3} m, within-group variance {:.3} m^2",
            n,
            groups.values().filter(|v| v.len() > 1).count(),
            dev / n as f64,
            sq / n as f64
        );
    }
    // Speeds (tier A only has recorded trajectories).
    println!(
        "\n| tier A case | recorded p95 / mean m/s | PX4 p95 / mean m/s | recorded / PX4 flight s |\n|---|---|---|---|"
    );
    let (mut rec_all, mut px4_all) = (Vec::new(), Vec::new());
    for r in rows.iter().filter(|r| r.tier == "A") {
        let rec = recorded_samples(&dir, &r.id);
        let flown = Trajectory::load_csv(&px4_dir.join("traj").join(format!("{}.csv", r.id)))
            .ok()
            .map(|t| t.samples.iter().map(|s| (s.t_s, s.x, s.y)).collect::<Vec<_>>());
        let (Some(rec), Some(flown)) = (rec, flown) else {
            continue;
        };
        let (Some(a), Some(b)) = (speeds(&rec), speeds(&flown)) else {
            continue;
        };
        let dur = |s: &[(f64, f64, f64)]| s.last().map_or(0.0, |l| l.0) - s.first().map_or(0.0, |f| f.0);
        println!(
            "| {} | {:.2} / {:.2} | {:.2} / {:.2} | {:.0} / {:.0} |",
            r.id,
            a.0,
            a.1,
            b.0,
            b.1,
            dur(&rec),
            dur(&flown)
        );
        rec_all.push(a);
        px4_all.push(b);
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "median over tier A: recorded p95 {:.2} mean {:.2} m/s; PX4 p95 {:.2} mean {:.2} m/s",
        med(&mut rec_all.iter().map(|s| s.0).collect()),
        med(&mut rec_all.iter().map(|s| s.1).collect()),
        med(&mut px4_all.iter().map(|s| s.0).collect()),
        med(&mut px4_all.iter().map(|s| s.1).collect()),
    );
    prequential(&rows);
    Ok(())
}

/// Prequential MAE of the bias learning for each prior weight, per truth.
fn prequential(rows: &[Row]) {
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    println!("\n| prior weight (flights) | recorded: first 25 / all | PX4: first 25 / all |\n|---|---|---|");
    for k in [0.0, 1.0, 2.0, 4.0, 8.0, 16.0, 1e9] {
        let mut cells = Vec::new();
        for truth in [|r: &Row| Some(r.real), |r: &Row| r.px4] {
            let (mut early, mut all) = (0.0, 0.0);
            let orders = 50;
            for seed in 0..orders {
                // Shuffle obstacle sets (repeats stay together, as a campaign never flies one set twice).
                let mut groups: BTreeMap<String, Vec<&Row>> = BTreeMap::new();
                for r in rows {
                    groups
                        .entry(r.group.clone().unwrap_or_else(|| r.id.clone()))
                        .or_default()
                        .push(r);
                }
                let mut keys: Vec<String> = groups.keys().cloned().collect();
                keys.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
                let pairs: Vec<(f64, f64)> = keys
                    .iter()
                    .flat_map(|k| groups[k].iter())
                    .filter_map(|r| Some((r.lfs_px4?, truth(r)?)))
                    .collect();
                let e = prequential_errors(&pairs, &Calibration::with_prior(0.0, k));
                early += e.iter().take(25).sum::<f64>() / e.len().min(25) as f64;
                all += e.iter().sum::<f64>() / e.len() as f64;
            }
            cells.push(format!("{:.3} / {:.3}", early / orders as f64, all / orders as f64));
        }
        let name = if k > 1e8 {
            "no learning".to_string()
        } else {
            format!("{k}")
        };
        println!("| {name} | {} | {} |", cells[0], cells[1]);
    }
}
