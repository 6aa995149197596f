//! Exploring or confirming: from campaign folders flown with `--confirm 3`, what a flight buys spent on a new
//! candidate against one spent confirming a test whose first flight failed. Prints, over every journal given:
//! the new candidates' failure rate `f`; for tests whose first flight failed, the share confirmed and the
//! flights their confirmation took, overall and by the first flight's distance; and the confirmed failing tests
//! per flight of each use.
//!
//! Also how well the failure probability ranks on this vehicle: the Brier score over first flights of the
//! ensemble's `predicted_p_fail`, of a constant rate, and of a normal model of the calibrated prediction whose
//! bias and spread are fitted on the campaign's earlier flights (in flight order, so each is out of sample).
//!
//! And, per folder, how well the predictions the campaign ranked by order its first flights: Spearman of the
//! prediction it flew each test on (calibrated, moved by the flights' kernel) and of the raw LFS against the
//! flown distance.
//!
//! `cargo run --release --example confirm_split -- FOLDER...` (campaign folders, each holding `journal.jsonl`)

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::Context;
use prgenuav::campaign::fly::confirm::failed;
use prgenuav::campaign::report::expected::expected_points::normal_cdf;
use prgenuav::campaign::store::journal::{FlightRecord, Journal};
use prgenuav::lfs::fidelity::aggregate;
use prgenuav::model::competition::FAIL_BELOW_M as FAIL_M;

/// First-flight distance bins (upper bounds, metres) of the failing first flights.
const BINS: [f64; 3] = [1.0, 1.25, 1.5];

/// A failing test's flights after its first: (its first flight's distance, confirmed, flights after the first).
fn confirmations(records: &[FlightRecord]) -> Vec<(f64, bool, usize)> {
    let mut by_test: BTreeMap<u64, Vec<&FlightRecord>> = BTreeMap::new();
    for r in records {
        by_test.entry(r.candidate.0).or_default().push(r);
    }
    by_test
        .values()
        .filter_map(|flights| {
            let first = flights.iter().find(|r| r.attempt == 0)?;
            let d1 = first.flown.min_distance.filter(|_| failed(first.flown.min_distance))?;
            let fails = flights.iter().filter(|r| failed(r.flown.min_distance)).count();
            // Settled only: a test whose third flight never came (budget spent) says nothing.
            let settled = fails >= 2 || flights.len() - fails >= 2;
            settled.then_some((d1, fails >= 2, flights.len() - 1))
        })
        .collect()
}

/// (normal model's p, ensemble's p, failed) of each first flight with an ensemble prediction, in flight order.
/// The model's prior: 0 m of extra bias and a 0.3 m spread, each weighing 3 flights.
fn probabilities(records: &[FlightRecord]) -> Vec<(f64, f64, bool)> {
    let mut residuals: Vec<f64> = Vec::new();
    let mut out = Vec::new();
    for r in records.iter().filter(|r| r.attempt == 0) {
        let (Some(flown), Some(predicted)) = (r.flown.min_distance, r.prediction.as_ref()) else {
            continue;
        };
        let n = residuals.len() as f64;
        let bias = residuals.iter().sum::<f64>() / (n + 3.0);
        let var = (3.0 * 0.09 + residuals.iter().map(|x| (x - bias).powi(2)).sum::<f64>()) / (n + 3.0);
        let q = normal_cdf((FAIL_M - (predicted.min_distance + bias)) / var.sqrt());
        if let Some(p) = predicted.p_fail {
            out.push((q, p, flown < FAIL_M));
        }
        residuals.push(flown - predicted.min_distance);
    }
    out
}

/// Spearman of the campaign's prediction and of the raw LFS against the flown distance, over `first`.
fn print_ranking(folder: &std::path::Path, first: &[&FlightRecord]) {
    let pairs = |p: &dyn Fn(&FlightRecord) -> Option<f64>| -> Vec<(f64, f64)> {
        first
            .iter()
            .filter_map(|r| Some((p(r)?, r.flown.min_distance?)))
            .collect()
    };
    let ranked = aggregate(&pairs(&|r| r.predicted_m()));
    let raw = aggregate(&pairs(&|r| r.prediction.as_ref()?.raw_min_distance));
    let show = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{x:.3}"));
    println!(
        "{}: {} first flights; Spearman against the flown distance: the campaign's prediction {}, the raw LFS {}",
        folder.display(),
        ranked.n,
        show(ranked.spearman),
        show(raw.spearman)
    );
}

fn brier(v: &[(f64, f64, bool)], p: impl Fn(&(f64, f64, bool)) -> f64) -> f64 {
    v.iter().map(|x| (p(x) - f64::from(u8::from(x.2))).powi(2)).sum::<f64>() / v.len().max(1) as f64
}

fn main() -> anyhow::Result<()> {
    let folders: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    anyhow::ensure!(!folders.is_empty(), "usage: confirm_split FOLDER...");
    let (mut fresh, mut fresh_failed, mut tests, mut probs) = (0usize, 0usize, Vec::new(), Vec::new());
    for folder in &folders {
        let path = folder.join("journal.jsonl");
        let records = Journal::read(&path).with_context(|| format!("reading {}", path.display()))?;
        let first: Vec<&FlightRecord> = records.iter().filter(|r| r.attempt == 0).collect();
        print_ranking(folder, &first);
        fresh += first.len();
        fresh_failed += first.iter().filter(|r| failed(r.flown.min_distance)).count();
        tests.extend(confirmations(&records));
        probs.extend(probabilities(&records));
    }
    let f = fresh_failed as f64 / fresh.max(1) as f64;
    println!("new candidates: {fresh_failed} of {fresh} first flights failed (f = {f:.3})");
    let row = |name: &str, t: &[&(f64, bool, usize)]| {
        let confirmed = t.iter().filter(|x| x.1).count();
        let flights: usize = t.iter().map(|x| x.2).sum();
        println!(
            "{name}: {} settled, {confirmed} confirmed ({:.2}), {flights} flights after the first ({:.2} each); \
             confirmed per confirming flight {:.3}",
            t.len(),
            confirmed as f64 / t.len().max(1) as f64,
            flights as f64 / t.len().max(1) as f64,
            confirmed as f64 / flights.max(1) as f64
        );
        (
            confirmed as f64 / t.len().max(1) as f64,
            flights as f64 / t.len().max(1) as f64,
        )
    };
    let all: Vec<&(f64, bool, usize)> = tests.iter().collect();
    let (p_confirm, extra) = row("failing first flights", &all);
    let mut low = 0.0;
    for high in BINS {
        let bin: Vec<&(f64, bool, usize)> = tests.iter().filter(|t| t.0 >= low && t.0 < high).collect();
        row(&format!("  first flight in [{low:.2}, {high:.2}) m"), &bin);
        low = high;
    }
    // A new candidate costs its flight plus, when it fails, its confirmation.
    let explore = f * p_confirm / (1.0 + f * extra);
    println!(
        "confirmed failing tests per flight: exploring (a new candidate, confirmed as above) {explore:.3}; \
         confirming a test whose first flight failed {:.3}",
        p_confirm / extra.max(f64::MIN_POSITIVE)
    );
    if probs.is_empty() {
        println!("Brier: no first flight with an ensemble's p_fail");
        return Ok(());
    }
    let rate = probs.iter().filter(|x| x.2).count() as f64 / probs.len() as f64;
    println!(
        "Brier over {} first flights with an ensemble: ensemble p_fail {:.3}, a constant rate ({rate:.3}) {:.3}, \
         normal model of the calibrated prediction {:.3}",
        probs.len(),
        brier(&probs, |x| x.1),
        brier(&probs, |_| rate),
        brier(&probs, |x| x.0)
    );
    Ok(())
}
