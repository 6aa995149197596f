//! The cross-validation of the expected-points weights (`examples/fit_expected.rs`): folds by obstacle set,
//! the weights chosen on the other folds by the mean absolute error of the predicted mean points of the tests
//! a campaign would write (at least one of the shown flights below 1.5 m), scored on the held-out fold.

use std::collections::HashMap;

use anyhow::Context;
use prgenuav::campaign::report::expected::expected_points::{Evidence, Weights, counts, estimate_with, skilled_prior};
use prgenuav::campaign::report::expected::score::NEIGHBOUR_IOU;
use prgenuav::geometry::{Footprint, union_iou};
use prgenuav::judge::points;
use prgenuav::model::Obstacle;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

/// A test flown many times.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Case {
    /// Its candidate id in the campaign.
    pub candidate: u64,
    /// Its obstacles.
    pub obstacles: Vec<Obstacle>,
    /// The campaign's prediction of its first flight, metres.
    pub predicted_m: f64,
    /// The evaluated flights' minimum distances, metres, in run order.
    pub runs: Vec<f64>,
}

/// The tests of one campaign (neighbours and residuals come from the same campaign only).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DataFile {
    /// Where the data came from.
    pub source: String,
    /// The tests.
    pub cases: Vec<Case>,
}

/// Flights the judge averages.
const JUDGED: usize = 5;
/// Shown flights: what a campaign has of a test.
const SHOWN: [usize; 3] = [1, 2, 3];
const FOLDS: usize = 5;
const SEED: u64 = 0;
const PRIORS: [f64; 9] = [0.0, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0];
const NEIGHBOURS: [f64; 5] = [0.0, 0.1, 0.25, 0.5, 1.0];
const CAPS: [f64; 4] = [0.5, 1.0, 2.0, 4.0];
/// The weights set from first principles before this fit, for comparison.
const FIRST_PRINCIPLES: Weights = Weights {
    prior_flights: 1.0,
    neighbour_weight: 0.25,
    max_neighbour_flights: 1.0,
};

/// One prediction to score: a test with `k` shown flights.
struct Item {
    fold: usize,
    k: usize,
    /// A shown flight earned points: the campaign would rank and write it.
    failed: bool,
    evidence: Evidence,
    /// Mean points of the next [`JUDGED`] flights.
    target: f64,
}

/// Mean absolute error, coverage of the 10-90 % intervals (of the expected points; of the judge's 5-flight
/// mean) and mean signed error over some items.
#[derive(Debug, Clone, Copy, Default)]
struct Score {
    n: usize,
    mae: f64,
    coverage: f64,
    judged_coverage: f64,
    bias: f64,
}

fn score<'a>(items: impl Iterator<Item = &'a Item>, w: &Weights) -> Score {
    let (mut n, mut abs, mut inside, mut judged, mut signed) = (0, 0.0, 0, 0, 0.0);
    for it in items {
        let e = estimate_with(&it.evidence, w);
        n += 1;
        abs += (e.mean - it.target).abs();
        signed += e.mean - it.target;
        inside += usize::from(e.low - 1e-9 <= it.target && it.target <= e.high + 1e-9);
        judged += usize::from(e.judged_low - 1e-9 <= it.target && it.target <= e.judged_high + 1e-9);
    }
    let per = |x: f64| if n == 0 { f64::NAN } else { x / n as f64 };
    Score {
        n,
        mae: per(abs),
        coverage: per(inside as f64),
        judged_coverage: per(judged as f64),
        bias: per(signed),
    }
}

fn grid() -> Vec<Weights> {
    let mut out = Vec::new();
    for &prior_flights in &PRIORS {
        for &neighbour_weight in &NEIGHBOURS {
            for &max_neighbour_flights in &CAPS {
                out.push(Weights {
                    prior_flights,
                    neighbour_weight,
                    max_neighbour_flights,
                });
            }
        }
    }
    out
}

/// Each obstacle set's fold: sets dealt round-robin in a seeded random order, so repeats never straddle folds.
fn folds(files: &[DataFile]) -> HashMap<String, usize> {
    let mut sets: Vec<String> = Vec::new();
    for c in files.iter().flat_map(|f| &f.cases) {
        let key = serde_json::to_string(&c.obstacles).unwrap_or_default();
        if !sets.contains(&key) {
            sets.push(key);
        }
    }
    sets.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(SEED));
    sets.into_iter().enumerate().map(|(i, s)| (s, i % FOLDS)).collect()
}

/// The items of one campaign with `k` shown flights per test.
fn items(file: &DataFile, k: usize, fold_of: &HashMap<String, usize>) -> Vec<Item> {
    let cases: Vec<&Case> = file.cases.iter().filter(|c| c.runs.len() >= k + JUDGED).collect();
    let prints: Vec<Vec<Footprint>> = cases
        .iter()
        .map(|c| c.obstacles.iter().map(Obstacle::footprint).collect())
        .collect();
    let pairs = |c: &Case| -> Vec<(f64, f64)> {
        let r = c.runs[..k].iter().map(|d| (c.predicted_m, *d));
        r.filter(|_| c.predicted_m.is_finite()).collect()
    };
    let pairs: Vec<Vec<(f64, f64)>> = cases.iter().map(|c| pairs(c)).collect();
    let mut out = Vec::with_capacity(cases.len());
    for (i, c) in cases.iter().enumerate() {
        let others = (0..cases.len()).filter(|&j| j != i);
        let near = others
            .clone()
            .filter(|&j| union_iou(&prints[i], &prints[j]) >= NEIGHBOUR_IOU);
        let neighbours = near.flat_map(|j| cases[j].runs[..k].iter().copied());
        let other_pairs: Vec<(f64, f64)> = others.flat_map(|j| pairs[j].iter().copied()).collect();
        let shown = &c.runs[..k];
        let judged = &c.runs[k..k + JUDGED];
        let key = serde_json::to_string(&c.obstacles).unwrap_or_default();
        out.push(Item {
            fold: fold_of.get(&key).copied().unwrap_or(0),
            k,
            failed: shown.iter().any(|&d| points(d) > 0),
            evidence: Evidence {
                own: counts(shown.iter().copied()),
                neighbours: counts(neighbours),
                prior: skilled_prior(c.predicted_m, &other_pairs),
            },
            target: judged.iter().map(|&d| f64::from(points(d))).sum::<f64>() / JUDGED as f64,
        });
    }
    out
}

/// The grid point with the lowest mean absolute error on the written tests among `items` (the first such
/// point in grid order on a tie).
fn best(items: &[&Item], grid: &[Weights]) -> Weights {
    let mut best = (f64::INFINITY, Weights::CHOSEN);
    for w in grid {
        let s = score(items.iter().copied().filter(|i| i.failed), w);
        if s.mae < best.0 {
            best = (s.mae, *w);
        }
    }
    best.1
}

fn show(w: &Weights) -> String {
    format!(
        "prior {} / neighbour {} / cap {}",
        w.prior_flights, w.neighbour_weight, w.max_neighbour_flights
    )
}

fn line(label: &str, written: Score, all: Score) -> String {
    format!(
        "| {label} | {:.3} | {:.2} | {:.2} | {:+.3} | {} | {:.3} | {:.2} | {:.2} | {} |",
        written.mae,
        written.coverage,
        written.judged_coverage,
        written.bias,
        written.n,
        all.mae,
        all.coverage,
        all.judged_coverage,
        all.n
    )
}

/// The cross-validated choice: each fold's items scored under the weights the other folds chose.
fn cross_validate(items: &[Item], grid: &[Weights]) -> (Score, Score, Vec<Weights>) {
    let mut chosen = Vec::new();
    let mut held: Vec<(&Item, Weights)> = Vec::new();
    for f in 0..FOLDS {
        let train: Vec<&Item> = items.iter().filter(|i| i.fold != f).collect();
        let w = best(&train, grid);
        chosen.push(w);
        held.extend(items.iter().filter(|i| i.fold == f).map(|i| (i, w)));
    }
    let pooled = |written: bool| {
        let mut parts = Vec::new();
        for (i, w) in held.iter().filter(|(i, _)| i.failed || !written) {
            parts.push(score(std::iter::once(*i), w));
        }
        let n = parts.len();
        let mean = |f: fn(&Score) -> f64| parts.iter().map(f).sum::<f64>() / n.max(1) as f64;
        Score {
            n,
            mae: mean(|s| s.mae),
            coverage: mean(|s| s.coverage),
            judged_coverage: mean(|s| s.judged_coverage),
            bias: mean(|s| s.bias),
        }
    };
    (pooled(true), pooled(false), chosen)
}

/// `fit_expected cv DATA.json...`: prints the cross-validated figure, then the grid in-sample.
pub fn run(paths: &[String]) -> anyhow::Result<()> {
    let mut files = Vec::new();
    for p in paths {
        let text = std::fs::read_to_string(p).with_context(|| format!("{p}: cannot read"))?;
        files.push(serde_json::from_str::<DataFile>(&text).with_context(|| format!("{p}: not fit_expected data"))?);
    }
    let fold_of = folds(&files);
    let mut all = Vec::new();
    for k in SHOWN {
        for f in &files {
            all.extend(items(f, k, &fold_of));
        }
    }
    let items = all;
    let grid = grid();
    let written = items.iter().filter(|i| i.failed).count();
    println!(
        "items (test x shown flights 1-3): {} ({written} would be written)",
        items.len()
    );
    let (cv_written, cv_all, chosen) = cross_validate(&items, &grid);
    for (f, w) in chosen.iter().enumerate() {
        println!("fold {f} chose {}", show(w));
    }
    let all_refs: Vec<&Item> = items.iter().collect();
    let whole = best(&all_refs, &grid);
    println!("all folds chose {}", show(&whole));
    println!("\n| weights | MAE written | coverage | judged coverage | bias | n | MAE all | coverage | judged | n |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    println!("{}", line("**cross-validated choice**", cv_written, cv_all));
    let row = |w: &Weights, note: &str| {
        let s = |f: fn(&Item) -> bool| score(items.iter().filter(|i| f(i)), w);
        line(&format!("{}{note}", show(w)), s(|i| i.failed), s(|_| true))
    };
    println!("{}", row(&whole, " (chosen on all folds, in-sample)"));
    println!("{}", row(&Weights::CHOSEN, " (current)"));
    println!("{}", row(&FIRST_PRINCIPLES, " (first principles)"));
    let mut ranked: Vec<(f64, Weights)> = (grid.iter())
        .map(|w| (score(items.iter().filter(|i| i.failed), w).mae, *w))
        .collect();
    ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("\nin-sample, best 12 and worst 3 of {} grid points:", grid.len());
    for (_, w) in ranked.iter().take(12).chain(ranked.iter().rev().take(3).rev()) {
        println!("{}", row(w, ""));
    }
    println!("\nin-sample, the prior's weight at neighbour 1 / cap 4:");
    for prior_flights in PRIORS {
        let w = Weights {
            prior_flights,
            neighbour_weight: 1.0,
            max_neighbour_flights: 4.0,
        };
        println!("{}", row(&w, ""));
    }
    println!("\nper shown flights, first principles / chosen on all (MAE written, coverage, n):");
    for k in SHOWN {
        let s = |w: &Weights| score(items.iter().filter(|i| i.failed && i.k == k), w);
        let (a, b) = (s(&FIRST_PRINCIPLES), s(&whole));
        println!(
            "k {k}: {:.3} {:.2} / {:.3} {:.2} (n {})",
            a.mae, a.coverage, b.mae, b.coverage, a.n
        );
    }
    Ok(())
}
