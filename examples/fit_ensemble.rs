//! Chooses the ensemble's perturbation scales and `p_fail` prior by 5-fold cross-validation with folds by
//! obstacle set (`fidelity::fold_of`: repeats of one set never straddle folds) on the recorded flights, and
//! reports the cross-validated ROC AUC and Brier score first, the in-sample ones beside.
//!
//! `cargo run --release --example fit_ensemble -- [N] [JOBS] [DIR]` (default 8 members, 2 threads,
//! `tests/data/hfs-flights`). Each grid point costs N x 127 simulations; the members' distances are cached per
//! grid point in `target/fit_ensemble/` and reused across folds and runs. The phase is not fitted: where the
//! frames fall within a tick is unknown, so a whole tick (uniform) is its honest scale.

use std::path::{Path, PathBuf};

use prgenuav::lfs::calibration::{brier, roc_auc};
use prgenuav::lfs::ensemble::{Ensemble, EnsembleParams};
use prgenuav::lfs::fidelity::{EnsembleSpec, FlightCase, case_ensemble, case_p_fail, fold_of, load_dir};
use prgenuav::lfs::sim::SimConfig;
use prgenuav::model::competition::FAIL_BELOW_M;

const FOLDS: usize = 5;
const SEED: u64 = 0;

/// The simulated grid: (delay jitter ticks, speed_rel, obstacle_pos_m, obstacle_yaw_deg): latency jitter off/on
/// x speed 3 / 10 % x box jitter small (2 cm, 1 degree) / large (10 cm, 5 degrees). Small because each point
/// costs N x 127 simulations (3-7 minutes on the shared 2-core VM).
const GRID: [(usize, f64, f64, f64); 8] = [
    (0, 0.03, 0.02, 1.0),
    (0, 0.03, 0.10, 5.0),
    (0, 0.10, 0.02, 1.0),
    (0, 0.10, 0.10, 5.0),
    (1, 0.03, 0.02, 1.0),
    (1, 0.03, 0.10, 5.0),
    (1, 0.10, 0.02, 1.0),
    (1, 0.10, 0.10, 5.0),
];
/// The prior's pseudo-counts (fail, pass): free to try, no simulation needed.
const PRIORS: [f64; 5] = [0.0, 0.25, 0.5, 1.0, 2.0];

fn params(g: (usize, f64, f64, f64), prior: (f64, f64)) -> EnsembleParams {
    EnsembleParams {
        phase_ticks: 1.0,
        delay_jitter_ticks: g.0,
        speed_rel: g.1,
        obstacle_pos_m: g.2,
        obstacle_yaw_deg: g.3,
        prior_fail: prior.0,
        prior_pass: prior.1,
    }
}

/// Members' distances of every case (`None` where the simulation could not run), from the cache or simulated.
fn members(cases: &[FlightCase], spec: &EnsembleSpec, jobs: usize, cache: &Path) -> Vec<Option<Vec<f64>>> {
    if let Ok(text) = std::fs::read_to_string(cache)
        && let Ok(v) = serde_json::from_str::<Vec<Option<Vec<f64>>>>(&text)
        && v.len() == cases.len()
    {
        return v;
    }
    let config = SimConfig::default();
    let mut out: Vec<Option<Vec<f64>>> = vec![None; cases.len()];
    std::thread::scope(|s| {
        let per = cases.len().div_ceil(jobs.max(1));
        for (t, chunk) in out.chunks_mut(per).enumerate() {
            let config = &config;
            s.spawn(move || {
                for (i, slot) in chunk.iter_mut().enumerate() {
                    *slot = case_ensemble(&cases[t * per + i], config, spec)
                        .ok()
                        .map(|e| e.member_min_distances);
                }
            });
        }
    });
    if let Ok(text) = serde_json::to_string(&out) {
        let _ = std::fs::write(cache, text);
    }
    out
}

/// `p_fail` of every case under `p` from cached members.
fn p_fails(cases: &[FlightCase], m: &[Option<Vec<f64>>], p: &EnsembleParams) -> Vec<Option<f64>> {
    cases
        .iter()
        .zip(m)
        .map(|(c, d)| {
            let e = Ensemble {
                member_min_distances: d.clone()?,
                fork_cycle: 0,
            };
            case_p_fail(c, &e, p)
        })
        .collect()
}

/// (AUC, Brier) over the cases `keep` selects.
fn score(cases: &[FlightCase], p: &[Option<f64>], keep: impl Fn(&FlightCase) -> bool) -> (Option<f64>, Option<f64>) {
    let (mut s, mut o) = (Vec::new(), Vec::new());
    for (c, p) in cases.iter().zip(p) {
        if let Some(p) = p
            && keep(c)
        {
            s.push(*p);
            o.push(c.real_m < FAIL_BELOW_M);
        }
    }
    (roc_auc(&s, &o), brier(&s, &o))
}

fn fmt(v: (Option<f64>, Option<f64>)) -> String {
    let f = |x: Option<f64>| x.map_or("-".into(), |x| format!("{x:.3}"));
    format!("AUC {} Brier {}", f(v.0), f(v.1))
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(Ok(8), |a| a.parse())?;
    let jobs: usize = args.get(2).map_or(Ok(2), |a| a.parse())?;
    let dir = PathBuf::from(args.get(3).map_or("tests/data/hfs-flights", String::as_str));
    let (cases, _) = load_dir(&dir)?;
    let cache_dir = PathBuf::from("target/fit_ensemble");
    std::fs::create_dir_all(&cache_dir)?;
    let tiers: Vec<String> = cases
        .iter()
        .map(|c| c.tier.clone())
        .collect::<std::collections::BTreeSet<_>>()
        .into_iter()
        .collect();

    // The point prediction as a 0/1 probability (N = 1, no perturbation): the baseline.
    let none = EnsembleSpec {
        params: EnsembleParams::none(),
        n: 1,
        seed: SEED,
    };
    let base = members(&cases, &none, jobs, &cache_dir.join("none.json"));
    println!(
        "point prediction as p_fail: {}",
        fmt(score(&cases, &p_fails(&cases, &base, &none.params), |_| true))
    );

    // Every (grid point, prior) candidate's p_fail per case.
    let mut candidates: Vec<(EnsembleParams, Vec<Option<f64>>)> = Vec::new();
    for g in GRID {
        let spec = EnsembleSpec {
            params: params(g, (0.0, 0.0)),
            n,
            seed: SEED,
        };
        let name = format!("n{n}_s{SEED}_d{}_v{}_p{}_y{}.json", g.0, g.1, g.2, g.3);
        let t = std::time::Instant::now();
        let m = members(&cases, &spec, jobs, &cache_dir.join(name));
        for a in PRIORS {
            for b in PRIORS {
                let p = params(g, (a, b));
                let pf = p_fails(&cases, &m, &p);
                candidates.push((p, pf));
            }
        }
        let plain = &candidates[candidates.len() - PRIORS.len() * PRIORS.len()].1;
        eprintln!(
            "grid {g:?}: {} (no prior), {:.0} s",
            fmt(score(&cases, plain, |_| true)),
            t.elapsed().as_secs_f64()
        );
    }

    // Lowest Brier on `train`; ties by higher AUC.
    let choose = |train: &dyn Fn(&FlightCase) -> bool| -> usize {
        let mut best = (f64::INFINITY, f64::NEG_INFINITY, 0);
        for (i, (_, pf)) in candidates.iter().enumerate() {
            let (auc, b) = score(&cases, pf, train);
            let (b, auc) = (b.unwrap_or(f64::INFINITY), auc.unwrap_or(0.0));
            if b < best.0 - 1e-12 || (b <= best.0 + 1e-12 && auc > best.1) {
                best = (b, auc, i);
            }
        }
        best.2
    };
    let mut held_out: Vec<Option<f64>> = vec![None; cases.len()];
    let mut chosen_per_fold = Vec::new();
    for f in 0..FOLDS {
        let i = choose(&|c: &FlightCase| fold_of(c, FOLDS) != f);
        chosen_per_fold.push(candidates[i].0);
        for (k, c) in cases.iter().enumerate() {
            if fold_of(c, FOLDS) == f {
                held_out[k] = candidates[i].1[k];
            }
        }
    }
    let all = choose(&|_: &FlightCase| true);
    let in_sample = &candidates[all].1;
    println!("{FOLDS}-fold cross-validated (folds by obstacle set), N = {n}, seed {SEED}:");
    println!(
        "  all      CV {}   in-sample {}",
        fmt(score(&cases, &held_out, |_| true)),
        fmt(score(&cases, in_sample, |_| true))
    );
    for t in &tiers {
        let cv = score(&cases, &held_out, |c| &c.tier == t);
        let ins = score(&cases, in_sample, |c| &c.tier == t);
        println!("  tier {t}   CV {}   in-sample {}", fmt(cv), fmt(ins));
    }
    for (f, p) in chosen_per_fold.iter().enumerate() {
        println!("  fold {f} chose {p:?}");
    }
    println!("chosen on all flights: {:?}", candidates[all].0);
    Ok(())
}
