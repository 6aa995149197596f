//! Honest figures for the motion model's fitted constants: k-fold cross-validation with folds by obstacle set,
//! and leave-one-tier-out.
//!
//! Every grid point simulates every recorded flight once ([`predict_grid`]); the folds then only choose among
//! cached predictions ([`cross_validate`]), so K folds cost no more simulation than one in-sample fit. In each
//! fold the constants with the lowest MAE on the other folds predict the held-out fold; the held-out
//! predictions of all folds are pooled into the cross-validated figure. Repeats of one obstacle set (the same
//! `repeat_group`, or the same boxes in several files) always share a fold, so a set's own repeats never help
//! predict it.

use std::collections::BTreeMap;

use serde::Serialize;

use super::fidelity::{Aggregates, FlightCase, aggregate, evaluate};
use crate::lfs::motion::{PaperParams, Px4Params};
use crate::lfs::sim::{MotionModel, SimConfig};

/// One candidate set of constants.
#[derive(Debug, Clone, PartialEq)]
pub struct GridPoint {
    /// Its constants in words.
    pub label: String,
    /// The motion model with them.
    pub motion: MotionModel,
}

/// The constants searched for `model` (`paper` or `px4`), always including the shipped defaults; `None` for
/// another name. Kept small: every point simulates every flight.
pub fn default_grid(model: &str) -> Option<Vec<GridPoint>> {
    let mut grid = Vec::new();
    match model {
        "paper" => {
            for speed in [1.5, 2.0, 3.0] {
                for yaw in [13.5, 30.0] {
                    for delay in [0, 1] {
                        let p = PaperParams {
                            max_speed_m_s: speed,
                            max_yaw_rate_deg_s: yaw,
                            delay_ticks: delay,
                            ..PaperParams::default()
                        };
                        grid.push(GridPoint {
                            label: format!("paper speed {speed} m/s, yaw {yaw} deg/s, delay {delay}"),
                            motion: MotionModel::Paper(p),
                        });
                    }
                }
            }
        }
        "px4" => {
            for gain in [0.3, 0.5, 0.95] {
                for delay in [0, 1] {
                    let p = Px4Params {
                        pos_gain_per_s: gain,
                        delay_ticks: delay,
                        ..Px4Params::default()
                    };
                    grid.push(GridPoint {
                        label: format!("px4 gain {gain} 1/s, delay {delay}"),
                        motion: MotionModel::Px4(p),
                    });
                }
            }
        }
        _ => return None,
    }
    Some(grid)
}

/// The key that keeps repeats together: the repeat group, else the obstacle set itself (boxes rounded to 1 cm,
/// so the same layout in two files is one set).
pub fn obstacle_set_key(case: &FlightCase) -> String {
    if let Some(g) = &case.repeat_group {
        return format!("group:{g}");
    }
    let mut boxes: Vec<String> = case
        .obstacles
        .iter()
        .map(|o| {
            let v = [
                o.size.l,
                o.size.w,
                o.size.h,
                o.position.x,
                o.position.y,
                o.position.z,
                o.position.r,
            ];
            v.iter().map(|x| format!("{:.2}", x)).collect::<Vec<_>>().join(",")
        })
        .collect();
    boxes.sort();
    format!("{}:{}", case.mission_name, boxes.join(";"))
}

/// Distinct obstacle sets among `cases` (see [`obstacle_set_key`]): at most this many folds.
pub fn obstacle_sets(cases: &[FlightCase]) -> usize {
    let mut keys: Vec<String> = cases.iter().map(obstacle_set_key).collect();
    keys.sort();
    keys.dedup();
    keys.len()
}

/// Fold (0..k) of each case: the obstacle sets are shuffled by a seeded hash and dealt round-robin, so folds
/// hold about the same number of sets and a set never straddles two folds. `None` if there are fewer sets
/// than folds or `k < 2`. (The ensemble's scales were fitted with [`super::fidelity::fold_of`] instead:
/// docs/design-constants.md#ensemble-perturbation-scales.)
pub fn assign_folds(cases: &[FlightCase], k: usize, seed: u64) -> Option<Vec<usize>> {
    let keys: Vec<String> = cases.iter().map(obstacle_set_key).collect();
    let mut sets: Vec<&String> = keys.iter().collect();
    sets.sort();
    sets.dedup();
    if k < 2 || sets.len() < k {
        return None;
    }
    sets.sort_by_key(|s| (crate::io::fnv1a(s.as_bytes(), seed), (*s).clone()));
    let fold_of: BTreeMap<&String, usize> = sets.iter().enumerate().map(|(i, s)| (*s, i % k)).collect();
    Some(keys.iter().map(|key| fold_of[key]).collect())
}

/// Predictions of every grid point for every case (`[point][case]`, the tier's definition; `None` where the
/// simulation could not run), simulated on up to `jobs` threads.
pub fn predict_grid(cases: &[FlightCase], grid: &[GridPoint], base: &SimConfig, jobs: usize) -> Vec<Vec<Option<f64>>> {
    grid.iter()
        .map(|g| {
            let config = SimConfig {
                motion: g.motion,
                ..base.clone()
            };
            evaluate(cases, Vec::new(), &config, jobs)
                .cases
                .into_iter()
                .map(|c| c.predicted)
                .collect()
        })
        .collect()
}

/// What a case contributes to the choice: its real distance and tier.
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// Real minimum distance, metres.
    pub real: f64,
    /// Tier letter.
    pub tier: String,
}

impl Truth {
    /// The truth of every case.
    pub fn of(cases: &[FlightCase]) -> Vec<Truth> {
        cases
            .iter()
            .map(|c| Truth {
                real: c.real_m,
                tier: c.tier.clone(),
            })
            .collect()
    }
}

fn pairs(preds: &[Option<f64>], truth: &[Truth], keep: impl Fn(usize) -> bool) -> Vec<(f64, f64)> {
    preds
        .iter()
        .zip(truth)
        .enumerate()
        .filter(|(i, _)| keep(*i))
        .filter_map(|(_, (p, t))| p.map(|p| (p, t.real)))
        .collect()
}

/// The grid point with the lowest MAE over the cases `keep` selects (ties: the earlier point); `None` if no
/// point predicts any of them.
pub fn choose(preds: &[Vec<Option<f64>>], truth: &[Truth], keep: impl Fn(usize) -> bool) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (g, p) in preds.iter().enumerate() {
        let Some(mae) = aggregate(&pairs(p, truth, &keep)).mae else {
            continue;
        };
        if best.is_none_or(|(_, b)| mae < b) {
            best = Some((g, mae));
        }
    }
    best.map(|(g, _)| g)
}

/// One fold's choice.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FoldChoice {
    /// The held-out part: a fold number, or a tier letter.
    pub held_out: String,
    /// Cases held out.
    pub n_held_out: usize,
    /// The constants chosen on the rest.
    pub chosen: String,
    /// Their figure on the held-out part.
    pub held_out_figure: Aggregates,
}

/// Cross-validated and in-sample figures of a grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CvReport {
    /// Folds.
    pub k: usize,
    /// Seed of the fold assignment.
    pub seed: u64,
    /// Distinct obstacle sets.
    pub obstacle_sets: usize,
    /// What the choice minimises on the training folds.
    pub criterion: &'static str,
    /// Held-out predictions of all folds pooled: the honest figure.
    pub cross_validated: Aggregates,
    /// The same per tier.
    pub cross_validated_tiers: BTreeMap<String, Aggregates>,
    /// Each fold's choice.
    pub folds: Vec<FoldChoice>,
    /// Each tier predicted with constants chosen on the other tiers.
    pub leave_one_tier_out: Vec<FoldChoice>,
    /// The constants chosen on all flights (what would ship).
    pub in_sample_chosen: String,
    /// Their figure on the same flights (optimistic).
    pub in_sample: Aggregates,
    /// The same per tier.
    pub in_sample_tiers: BTreeMap<String, Aggregates>,
    /// Every grid point's in-sample figure.
    pub grid: Vec<(String, Aggregates)>,
}

fn per_tier(preds: &[Option<f64>], truth: &[Truth]) -> BTreeMap<String, Aggregates> {
    let mut tiers: Vec<&str> = truth.iter().map(|t| t.tier.as_str()).collect();
    tiers.sort();
    tiers.dedup();
    tiers
        .into_iter()
        .map(|tier| {
            (
                tier.to_string(),
                aggregate(&pairs(preds, truth, |i| truth[i].tier == tier)),
            )
        })
        .collect()
}

/// Cross-validates the choice among `grid` (`preds[point][case]`) with `folds[case]` in `0..k`.
pub fn cross_validate(
    grid: &[GridPoint],
    preds: &[Vec<Option<f64>>],
    truth: &[Truth],
    folds: &[usize],
    k: usize,
    seed: u64,
    obstacle_sets: usize,
) -> Option<CvReport> {
    let label = |g: usize| grid.get(g).map_or_else(|| format!("point {g}"), |p| p.label.clone());
    let mut pooled: Vec<Option<f64>> = vec![None; truth.len()];
    let mut fold_choices = Vec::new();
    for f in 0..k {
        let g = choose(preds, truth, |i| folds[i] != f)?;
        for (i, slot) in pooled.iter_mut().enumerate() {
            if folds[i] == f {
                *slot = preds[g][i];
            }
        }
        fold_choices.push(FoldChoice {
            held_out: format!("fold {f}"),
            n_held_out: folds.iter().filter(|&&x| x == f).count(),
            chosen: label(g),
            held_out_figure: aggregate(&pairs(&preds[g], truth, |i| folds[i] == f)),
        });
    }
    let loto = leave_one_tier_out(preds, truth, &label);
    let all = choose(preds, truth, |_| true)?;
    Some(CvReport {
        k,
        seed,
        obstacle_sets,
        criterion: "lowest MAE on the training flights",
        cross_validated: aggregate(&pairs(&pooled, truth, |_| true)),
        cross_validated_tiers: per_tier(&pooled, truth),
        folds: fold_choices,
        leave_one_tier_out: loto,
        in_sample_chosen: label(all),
        in_sample: aggregate(&pairs(&preds[all], truth, |_| true)),
        in_sample_tiers: per_tier(&preds[all], truth),
        grid: preds
            .iter()
            .enumerate()
            .map(|(g, p)| (label(g), aggregate(&pairs(p, truth, |_| true))))
            .collect(),
    })
}

/// Each tier held out in turn: the grid point chosen on the other tiers, and its figure on the held-out one.
fn leave_one_tier_out(preds: &[Vec<Option<f64>>], truth: &[Truth], label: &dyn Fn(usize) -> String) -> Vec<FoldChoice> {
    let mut tiers: Vec<&str> = truth.iter().map(|t| t.tier.as_str()).collect();
    tiers.sort();
    tiers.dedup();
    let mut loto = Vec::new();
    for tier in tiers {
        let Some(g) = choose(preds, truth, |i| truth[i].tier != tier) else {
            continue;
        };
        loto.push(FoldChoice {
            held_out: format!("tier {tier}"),
            n_held_out: truth.iter().filter(|t| t.tier == tier).count(),
            chosen: label(g),
            held_out_figure: aggregate(&pairs(&preds[g], truth, |i| truth[i].tier == tier)),
        });
    }
    loto
}

#[cfg(test)]
#[path = "cv_tests.rs"]
mod tests;
