//! The competition bench's fit: each candidate setting flew the recorded cases of tiers A and B (one folder of
//! `examples/px4_reference.rs` output per candidate); this prints each candidate's figures against the
//! recorded flights (the targets), then chooses the candidate by 5-fold cross-validation with folds by
//! obstacle set (`fidelity::fold_of`): in each fold the candidate with the lowest objective on the other four
//! folds is chosen and judged on the held-out one, and the held-out flights are pooled. The objective is the
//! median absolute error of the judged distance plus |ln(median flight-time ratio)|, both on the training
//! folds. Candidates named `info:...` are reported but never chosen (settings fixed from code, not fitted). Each
//! other candidate is also compared case by case with the first one (median difference, sign test).
//!
//! `cargo run --release --example bench_fit -- DIR NAME=PX4_DIR [NAME=PX4_DIR ...]`; a `NAME=FILE.json` is the LFS's
//! per-case predictions instead (`prgenuav fidelity DIR --json`), landed ones only, with no flight time.

#[path = "common/flight_stats.rs"]
#[allow(dead_code)] // shared with competition_flights; this example needs only its median
mod flight_stats;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use prgenuav::lfs::fidelity::{FlightCase, aggregate, fold_of, load_dir};
use prgenuav::lfs::px4_flights;

const FOLDS: usize = 5;
/// The competition's verdict: a test fails below this judged distance.
const FAIL_M: f64 = 1.5;

/// One case flown by one candidate: (flown distance, recorded distance, flown / recorded time).
#[derive(Debug, Clone, Copy)]
struct Flown {
    px4_m: f64,
    real_m: f64,
    time_ratio: Option<f64>,
}

/// The median (the two middle values' mean for an even count); `None` when empty.
fn median(v: Vec<f64>) -> Option<f64> {
    (!v.is_empty()).then(|| flight_stats::median(&v))
}

/// The targets' figures of `rows`: n, median |error|, median error, Spearman, same verdict, median time ratio.
fn figures(rows: &[Flown]) -> String {
    let pairs: Vec<(f64, f64)> = rows.iter().map(|r| (r.px4_m, r.real_m)).collect();
    let f = |v: Option<f64>, unit: &str| v.map_or("-".to_string(), |v| format!("{v:+.3}{unit}"));
    let abs = median(pairs.iter().map(|(p, t)| (p - t).abs()).collect());
    let signed = median(pairs.iter().map(|(p, t)| p - t).collect());
    let same = pairs.iter().filter(|(p, t)| (*p < FAIL_M) == (*t < FAIL_M)).count();
    let ratios: Vec<f64> = rows.iter().filter_map(|r| r.time_ratio).collect();
    format!(
        "| {} | {} | {} | {} | {} of {} ({:.0} %) | {} ({} flights) |",
        pairs.len(),
        abs.map_or("-".into(), |v| format!("{v:.3} m")),
        f(signed, " m"),
        aggregate(&pairs).spearman.map_or("-".into(), |s| format!("{s:.3}")),
        same,
        pairs.len(),
        100.0 * same as f64 / pairs.len().max(1) as f64,
        median(ratios.clone()).map_or("-".into(), |r| format!("{r:.2}")),
        ratios.len()
    )
}

/// The objective on `rows` (lower is better).
fn objective(rows: &[Flown]) -> f64 {
    let abs = median(rows.iter().map(|r| (r.px4_m - r.real_m).abs()).collect()).unwrap_or(f64::INFINITY);
    let ratio = median(rows.iter().filter_map(|r| r.time_ratio).collect()).unwrap_or(f64::NAN);
    abs + if ratio > 0.0 { ratio.ln().abs() } else { f64::INFINITY }
}

fn recorded_duration(dir: &Path, id: &str) -> Option<f64> {
    let text = std::fs::read_to_string(dir.join(format!("{id}.json"))).ok()?;
    serde_json::from_str::<serde_json::Value>(&text).ok()?["duration_s"]
        .as_f64()
        .filter(|d| *d > 0.0)
}

/// A candidate's landed flights, by case id.
fn candidate(dir: &Path, px4_dir: &Path, cases: &[FlightCase]) -> anyhow::Result<BTreeMap<String, Flown>> {
    let flights = px4_flights::load(px4_dir, cases)?;
    let real: BTreeMap<&str, f64> = cases.iter().map(|c| (c.id.as_str(), c.real_m)).collect();
    Ok(flights
        .into_iter()
        .filter(|f| f.status == "landed")
        .filter_map(|f| {
            let flown = Flown {
                px4_m: f.min_distance?,
                real_m: *real.get(f.id.as_str())?,
                time_ratio: recorded_duration(dir, &f.id)
                    .map(|d| f.flight_time_s / d)
                    .filter(|r| *r > 0.0),
            };
            Some((f.id, flown))
        })
        .collect())
}

/// The LFS's landed predictions of `cases` from `prgenuav fidelity --json` output (no flight times).
fn lfs_candidate(file: &Path, cases: &[FlightCase]) -> anyhow::Result<BTreeMap<String, Flown>> {
    let text = std::fs::read_to_string(file).map_err(|e| anyhow::anyhow!("{}: {e}", file.display()))?;
    let report: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| anyhow::anyhow!("{}: not JSON: {e}", file.display()))?;
    let rows = report["cases"]
        .as_array()
        .ok_or_else(|| anyhow::anyhow!("{}: no `cases` array (expected `fidelity --json`)", file.display()))?;
    let real: BTreeMap<&str, f64> = cases.iter().map(|c| (c.id.as_str(), c.real_m)).collect();
    Ok(rows
        .iter()
        .filter(|r| r["status"] == "landed")
        .filter_map(|r| {
            let id = r["id"].as_str()?;
            let flown = Flown {
                px4_m: r["predicted"].as_f64()?,
                real_m: *real.get(id)?,
                time_ratio: None,
            };
            Some((id.to_string(), flown))
        })
        .collect())
}

/// Exact two-sided sign test: the chance of a split at least as uneven as `a` against `b` when both are equally
/// likely.
fn sign_test_p(a: usize, b: usize) -> f64 {
    let n = a + b;
    let mut choose = 1.0_f64; // C(n, j), built up term by term
    let mut tail = 0.0;
    for j in 0..=a.min(b) {
        if j > 0 {
            choose *= (n + 1 - j) as f64 / j as f64;
        }
        tail += choose;
    }
    (2.0 * tail / 2.0_f64.powi(n as i32)).min(1.0)
}

/// Each fitted candidate's distances against the first one's, case by case (both landed): the median
/// difference, how many came closer or went wider, and the sign test's p.
fn paired(fitted: &[&(String, BTreeMap<String, Flown>)]) {
    let Some((base_name, base)) = fitted.first().map(|c| (&c.0, &c.1)) else {
        return;
    };
    println!("\n### Paired against {base_name} (cases both landed)\n");
    println!("| candidate | n | median difference | closer | wider | sign test p |");
    println!("|---|---|---|---|---|---|");
    for (name, rows) in &fitted[1..] {
        let d: Vec<f64> = rows
            .iter()
            .filter_map(|(id, r)| base.get(id).map(|b| r.px4_m - b.px4_m))
            .collect();
        let (closer, wider) = (
            d.iter().filter(|x| **x < 0.0).count(),
            d.iter().filter(|x| **x > 0.0).count(),
        );
        let med = median(d.clone()).map_or("-".into(), |m| format!("{m:+.3} m"));
        println!(
            "| {name} | {} | {med} | {closer} | {wider} | {:.3} |",
            d.len(),
            sign_test_p(closer, wider)
        );
    }
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().ok_or_else(|| anyhow::anyhow!("DIR NAME=PX4_DIR ..."))?);
    let (cases, _) = load_dir(&dir)?;
    let cases: Vec<FlightCase> = cases
        .into_iter()
        .filter(|c| !c.obstacles.is_empty() && (c.tier == "A" || c.tier == "B"))
        .collect();
    let mut named: Vec<(String, BTreeMap<String, Flown>)> = Vec::new();
    for a in args {
        let (name, d) = a
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("{a:?} is not NAME=PX4_DIR"))?;
        let rows = if d.ends_with(".json") {
            lfs_candidate(Path::new(d), &cases)?
        } else {
            candidate(&dir, Path::new(d), &cases)?
        };
        named.push((name.to_string(), rows));
    }
    let fold: BTreeMap<&str, usize> = cases.iter().map(|c| (c.id.as_str(), fold_of(c, FOLDS))).collect();
    println!("{} recorded cases of tiers A and B with obstacles\n", cases.len());
    println!("| candidate | n | median abs error | median signed error | Spearman | same verdict | time ratio |");
    println!("|---|---|---|---|---|---|---|");
    for (name, rows) in &named {
        let v: Vec<Flown> = rows.values().copied().collect();
        println!("| {name} {} objective {:.3}", figures(&v), objective(&v));
    }
    let fitted: Vec<&(String, BTreeMap<String, Flown>)> =
        named.iter().filter(|(n, _)| !n.starts_with("info:")).collect();
    if fitted.is_empty() {
        return Ok(());
    }
    paired(&fitted);
    let mut held_out: Vec<Flown> = Vec::new();
    println!("\n### Cross-validated choice ({FOLDS} folds by obstacle set)\n");
    for k in 0..FOLDS {
        let train = |rows: &BTreeMap<String, Flown>| -> Vec<Flown> {
            rows.iter()
                .filter(|(id, _)| fold[id.as_str()] != k)
                .map(|(_, r)| *r)
                .collect()
        };
        let Some((name, rows)) = fitted
            .iter()
            .map(|c| (c, objective(&train(&c.1))))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(c, _)| (&c.0, &c.1))
        else {
            continue;
        };
        let test: Vec<Flown> = rows
            .iter()
            .filter(|(id, _)| fold[id.as_str()] == k)
            .map(|(_, r)| *r)
            .collect();
        println!(
            "fold {k}: chose {name} on {} training flights; {} held out",
            train(rows).len(),
            test.len()
        );
        held_out.extend(test);
    }
    println!(
        "\n| held out, pooled | n | median abs error | median signed error | Spearman | same verdict | time ratio |"
    );
    println!("|---|---|---|---|---|---|---|");
    println!("| cross-validated {}", figures(&held_out));
    Ok(())
}
