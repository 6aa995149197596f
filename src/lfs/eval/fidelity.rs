//! How well the simulator predicts real flights: reads the competition's recorded flights (the JSON format of
//! `hfs-flights/`), simulates each with the same mission and obstacles, and compares minimum distances
//! (mean absolute error, Spearman rank correlation, precision and recall of "below 1.5 m"), overall and per tier.
//!
//! Ground truth per tier: A = the printed Aerialist value (the digitised one when none was printed);
//! B = Aerialist's newer definition, which subtracts half the vehicle width (0.125 m), so our prediction is
//! converted to it (`max(0, d - 0.125)`) before comparing; C = the generator's logged Aerialist value.

use std::collections::BTreeMap;

use serde::Serialize;

use super::calibration::{brier, roc_auc};
use super::ensemble::{Ensemble, EnsembleError, EnsembleParams, run_ensemble};
use crate::lfs::sim::{SimConfig, SimStatus, simulate_parts};

pub use super::recorded::{DEFAULT_HEIGHT_M, FidelityError, FlightCase, competition_params, load_dir, load_flight};
use crate::model::competition::FAIL_BELOW_M;

/// One compared flight.
#[derive(Debug, Clone, Serialize)]
pub struct CaseResult {
    /// Flight id.
    pub id: String,
    /// Tier letter.
    pub tier: String,
    /// Mission name.
    pub mission: String,
    /// Real minimum distance (tier's definition), metres.
    pub real: f64,
    /// Predicted minimum distance (same definition), metres; `None` if the simulation could not run.
    pub predicted: Option<f64>,
    /// How the simulated flight ended.
    pub status: Option<SimStatus>,
    /// |predicted - real|, metres.
    pub abs_error: Option<f64>,
    /// Probability of "below 1.5 m" (tier's definition) from the ensemble, when one ran.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub p_fail: Option<f64>,
}

/// Agreement over a set of cases.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Aggregates {
    /// Cases with a prediction.
    pub n: usize,
    /// Mean absolute error, metres.
    pub mae: Option<f64>,
    /// Spearman rank correlation of predicted vs real.
    pub spearman: Option<f64>,
    /// Of the cases predicted below 1.5 m, the fraction really below 1.5 m.
    pub precision: Option<f64>,
    /// Of the cases really below 1.5 m, the fraction predicted below 1.5 m.
    pub recall: Option<f64>,
    /// ROC AUC of `p_fail` against "really below 1.5 m" (with an ensemble and both outcomes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auc: Option<f64>,
    /// Brier score of `p_fail` (with an ensemble).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub brier: Option<f64>,
}

/// The whole comparison.
#[derive(Debug, Clone, Serialize)]
pub struct FidelityReport {
    /// Per flight.
    pub cases: Vec<CaseResult>,
    /// Overall mean absolute error, metres.
    pub mae: Option<f64>,
    /// Overall Spearman rank correlation.
    pub spearman: Option<f64>,
    /// Overall precision of "below 1.5 m".
    pub precision: Option<f64>,
    /// Overall recall of "below 1.5 m".
    pub recall: Option<f64>,
    /// Overall ROC AUC of `p_fail` (with an ensemble).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub auc: Option<f64>,
    /// Overall Brier score of `p_fail` (with an ensemble).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub brier: Option<f64>,
    /// Per tier.
    pub tiers: BTreeMap<String, Aggregates>,
    /// How much the real simulator disagrees with itself: mean |d_i - d_j| over pairs of flights of the same
    /// obstacle set (`None` without repeats).
    pub hfs_repeat_mae: Option<f64>,
    /// Files without obstacles or a recorded distance.
    pub skipped: Vec<String>,
}

/// Ranks with ties averaged (1-based).
fn ranks(v: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
            j += 1;
        }
        let avg = (i + j) as f64 / 2.0 + 1.0;
        for k in &idx[i..=j] {
            r[*k] = avg;
        }
        i = j + 1;
    }
    r
}

/// Spearman's rank correlation (Pearson on tie-averaged ranks); `None` for fewer than 2 pairs or no spread.
pub fn spearman(a: &[f64], b: &[f64]) -> Option<f64> {
    if a.len() != b.len() || a.len() < 2 {
        return None;
    }
    let (ra, rb) = (ranks(a), ranks(b));
    let n = a.len() as f64;
    let (ma, mb) = (ra.iter().sum::<f64>() / n, rb.iter().sum::<f64>() / n);
    let cov: f64 = ra.iter().zip(&rb).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = ra.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = rb.iter().map(|y| (y - mb).powi(2)).sum();
    (va > 0.0 && vb > 0.0).then(|| cov / (va * vb).sqrt())
}

/// MAE, Spearman, precision and recall over `(predicted, real)` pairs.
pub fn aggregate(pairs: &[(f64, f64)]) -> Aggregates {
    let n = pairs.len();
    let mae = (n > 0).then(|| pairs.iter().map(|(p, r)| (p - r).abs()).sum::<f64>() / n as f64);
    let (p, r): (Vec<f64>, Vec<f64>) = pairs.iter().copied().unzip();
    let tp = pairs
        .iter()
        .filter(|(p, r)| *p < FAIL_BELOW_M && *r < FAIL_BELOW_M)
        .count();
    let pred_pos = pairs.iter().filter(|(p, _)| *p < FAIL_BELOW_M).count();
    let real_pos = pairs.iter().filter(|(_, r)| *r < FAIL_BELOW_M).count();
    Aggregates {
        n,
        mae,
        spearman: spearman(&p, &r),
        precision: (pred_pos > 0).then(|| tp as f64 / pred_pos as f64),
        recall: (real_pos > 0).then(|| tp as f64 / real_pos as f64),
        auc: None,
        brier: None,
    }
}

/// ROC AUC and Brier score of `(p_fail, real)` pairs against "really below 1.5 m".
pub fn probability_scores(pairs: &[(f64, f64)]) -> (Option<f64>, Option<f64>) {
    let (p, real): (Vec<f64>, Vec<f64>) = pairs.iter().copied().unzip();
    let fail: Vec<bool> = real.iter().map(|r| *r < FAIL_BELOW_M).collect();
    (roc_auc(&p, &fail), brier(&p, &fail))
}

/// Which of two fixed halves (0 or 1) a case belongs to, for fitting constants on one half and checking them on
/// the other: a hash (FNV-1a) of the repeat group, or of the id without one, so that repeats of one obstacle set
/// never straddle the halves and the split does not depend on file order.
pub fn split_half(case: &FlightCase) -> usize {
    fold_of(case, 2)
}

/// Which of `k` folds (0..k) a case belongs to for k-fold cross-validation: the same hash as [`split_half`],
/// so repeats of one obstacle set always share a fold.
pub fn fold_of(case: &FlightCase, k: usize) -> usize {
    let key = case.repeat_group.as_deref().unwrap_or(&case.id);
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in key.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    ((h >> 7) % k.max(1) as u64) as usize
}

/// Aggregates of `report` over the cases of half `half` (see [`split_half`]); `cases` are the evaluated cases
/// in the report's order.
pub fn aggregate_half(report: &FidelityReport, cases: &[FlightCase], half: usize) -> Aggregates {
    let pairs: Vec<(f64, f64)> = report
        .cases
        .iter()
        .zip(cases)
        .filter(|(_, c)| split_half(c) == half)
        .filter_map(|(r, _)| r.predicted.map(|p| (p, r.real)))
        .collect();
    aggregate(&pairs)
}

/// Mean |d_i - d_j| over pairs within each repeat group.
fn repeat_mae(cases: &[FlightCase]) -> Option<f64> {
    let mut groups: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for c in cases {
        if let Some(g) = &c.repeat_group {
            groups.entry(g).or_default().push(c.real_m);
        }
    }
    let mut diffs = Vec::new();
    for v in groups.values() {
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                diffs.push((v[i] - v[j]).abs());
            }
        }
    }
    (!diffs.is_empty()).then(|| diffs.iter().sum::<f64>() / diffs.len() as f64)
}

/// An ensemble to run for every case.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnsembleSpec {
    /// Perturbation scales and prior.
    pub params: EnsembleParams,
    /// Members per case.
    pub n: usize,
    /// Seed (every case uses the same seed: its members draw streams 0..n).
    pub seed: u64,
}

/// The recorded distances are the 2025 edition's (bare path), so predictions are judged by it too.
fn recorded_judge(config: &SimConfig) -> SimConfig {
    SimConfig {
        judge: crate::judge::Judge::E2025,
        ..config.clone()
    }
}

/// The ensemble of one case (members judged by the 2025 edition, centre-line distances).
pub fn case_ensemble(case: &FlightCase, config: &SimConfig, spec: &EnsembleSpec) -> Result<Ensemble, EnsembleError> {
    let c = recorded_judge(config);
    run_ensemble(
        &case.mission,
        &case.obstacles,
        &case.params,
        &c,
        &spec.params,
        spec.n,
        spec.seed,
        1,
    )
}

/// `p_fail` of a case's ensemble in the tier's definition (`max(0, d - offset) < 1.5`).
pub fn case_p_fail(case: &FlightCase, ensemble: &Ensemble, params: &EnsembleParams) -> Option<f64> {
    ensemble.p_fail_below(params, FAIL_BELOW_M + case.definition_offset_m)
}

/// Simulates one case and compares.
///
/// The recorded distances are the 2025 edition's (bare path), so the prediction is judged by it too, whatever
/// `config.judge` says.
pub fn evaluate_case(case: &FlightCase, config: &SimConfig) -> CaseResult {
    evaluate_case_with(case, config, None)
}

/// As [`evaluate_case`], with `p_fail` from `ensemble` when given.
pub fn evaluate_case_with(case: &FlightCase, config: &SimConfig, ensemble: Option<&EnsembleSpec>) -> CaseResult {
    let p_fail = ensemble.and_then(|spec| {
        let e = case_ensemble(case, config, spec).ok()?;
        case_p_fail(case, &e, &spec.params)
    });
    let config = &recorded_judge(config);
    let sim = simulate_parts(&case.mission, &case.obstacles, &case.params, config).ok();
    let predicted = sim
        .as_ref()
        .and_then(|s| s.distance.as_ref())
        .map(|d| (d.min_distance - case.definition_offset_m).max(0.0));
    CaseResult {
        id: case.id.clone(),
        tier: case.tier.clone(),
        mission: case.mission_name.clone(),
        real: case.real_m,
        predicted,
        status: sim.map(|s| s.status),
        abs_error: predicted.map(|p| (p - case.real_m).abs()),
        p_fail,
    }
}

/// Simulates every case on up to `jobs` threads (in input order) and aggregates.
pub fn evaluate(cases: &[FlightCase], skipped: Vec<String>, config: &SimConfig, jobs: usize) -> FidelityReport {
    evaluate_with(cases, skipped, config, None, jobs)
}

/// As [`evaluate`], with `p_fail`, AUC and Brier from `ensemble` when given.
pub fn evaluate_with(
    cases: &[FlightCase],
    skipped: Vec<String>,
    config: &SimConfig,
    ensemble: Option<&EnsembleSpec>,
    jobs: usize,
) -> FidelityReport {
    let jobs = jobs.clamp(1, cases.len().max(1));
    let mut results: Vec<Option<CaseResult>> = vec![None; cases.len()];
    std::thread::scope(|s| {
        let chunks: Vec<_> = results.chunks_mut(cases.len().div_ceil(jobs).max(1)).collect();
        let mut start = 0;
        for chunk in chunks {
            let from = start;
            start += chunk.len();
            s.spawn(move || {
                for (k, slot) in chunk.iter_mut().enumerate() {
                    *slot = Some(evaluate_case_with(&cases[from + k], config, ensemble));
                }
            });
        }
    });
    let results: Vec<CaseResult> = results.into_iter().flatten().collect();
    report(results, cases, skipped)
}

fn report(results: Vec<CaseResult>, cases: &[FlightCase], skipped: Vec<String>) -> FidelityReport {
    let pairs = |tier: Option<&str>| -> Vec<(f64, f64)> {
        results
            .iter()
            .filter(|c| tier.is_none_or(|t| c.tier == t))
            .filter_map(|c| c.predicted.map(|p| (p, c.real)))
            .collect()
    };
    let with_probability = |tier: Option<&str>| {
        let mut a = aggregate(&pairs(tier));
        let p: Vec<(f64, f64)> = results
            .iter()
            .filter(|c| tier.is_none_or(|t| c.tier == t))
            .filter_map(|c| c.p_fail.map(|p| (p, c.real)))
            .collect();
        (a.auc, a.brier) = probability_scores(&p);
        a
    };
    let all = with_probability(None);
    let mut tiers = BTreeMap::new();
    for c in &results {
        tiers
            .entry(c.tier.clone())
            .or_insert_with(|| with_probability(Some(&c.tier)));
    }
    FidelityReport {
        mae: all.mae,
        spearman: all.spearman,
        precision: all.precision,
        recall: all.recall,
        auc: all.auc,
        brier: all.brier,
        tiers,
        hfs_repeat_mae: repeat_mae(cases),
        skipped,
        cases: results,
    }
}

#[cfg(test)]
#[path = "fidelity_tests.rs"]
mod tests;
