use proptest::prelude::*;

use super::*;
use crate::lfs::eval::fidelity::load_dir;

fn truth(v: &[(f64, &str)]) -> Vec<Truth> {
    v.iter()
        .map(|(real, tier)| Truth {
            real: *real,
            tier: tier.to_string(),
        })
        .collect()
}

fn grid(n: usize) -> Vec<GridPoint> {
    (0..n)
        .map(|i| GridPoint {
            label: format!("g{i}"),
            motion: MotionModel::Paper(PaperParams::default()),
        })
        .collect()
}

#[test]
fn choose_takes_the_lowest_training_mae() {
    let t = truth(&[(1.0, "A"), (2.0, "A"), (3.0, "C")]);
    let preds = vec![
        vec![Some(1.0), Some(2.0), Some(9.0)], // perfect on 0, 1; far off on 2
        vec![Some(1.5), Some(2.5), Some(3.0)], // 0.5 off on 0, 1; perfect on 2
    ];
    assert_eq!(choose(&preds, &t, |i| i < 2), Some(0));
    assert_eq!(choose(&preds, &t, |i| i == 2), Some(1));
    assert_eq!(choose(&preds, &t, |_| true), Some(1), "MAE 2.0 vs 0.33");
    assert_eq!(choose(&[vec![None, None, None]], &t, |_| true), None);
}

/// A grid point that is perfect on tier A only wins in-sample when A dominates, but cross-validation reports
/// what the choice made without the held-out flights scores on them.
#[test]
fn cross_validation_scores_held_out_choices_only() {
    let t = truth(&[(1.0, "A"), (1.0, "A"), (2.0, "C"), (2.0, "C")]);
    let preds = vec![
        vec![Some(1.0), Some(1.0), Some(3.0), Some(3.0)], // MAE 0.5 overall
        vec![Some(2.0), Some(2.0), Some(2.0), Some(2.0)], // MAE 0.5 overall, perfect on C
        vec![Some(1.2), Some(1.2), Some(2.2), Some(2.2)], // MAE 0.2 overall: the in-sample choice
    ];
    let folds = [0, 1, 0, 1];
    let r = cross_validate(&grid(3), &preds, &t, &folds, 2, 0, 4).expect("report");
    assert_eq!(r.in_sample_chosen, "g2");
    assert!((r.in_sample.mae.expect("mae") - 0.2).abs() < 1e-12);
    // Each fold's training half has one A and one C flight: g2 wins there too, so the pooled figure is g2's.
    assert_eq!(
        r.folds.iter().map(|f| f.chosen.as_str()).collect::<Vec<_>>(),
        ["g2", "g2"]
    );
    assert!((r.cross_validated.mae.expect("mae") - 0.2).abs() < 1e-12);
    // Leave-one-tier-out: trained on C alone, g1 (perfect on C) is chosen and scores 1.0 on A.
    let a = r
        .leave_one_tier_out
        .iter()
        .find(|f| f.held_out == "tier A")
        .expect("tier A");
    assert_eq!(a.chosen, "g1");
    assert!((a.held_out_figure.mae.expect("mae") - 1.0).abs() < 1e-12);
    let c = r
        .leave_one_tier_out
        .iter()
        .find(|f| f.held_out == "tier C")
        .expect("tier C");
    assert_eq!(c.chosen, "g0");
    assert!((c.held_out_figure.mae.expect("mae") - 1.0).abs() < 1e-12);
}

#[test]
fn a_fold_without_a_usable_choice_gives_no_report() {
    let t = truth(&[(1.0, "A"), (2.0, "A")]);
    let preds = vec![vec![Some(1.0), None]];
    // Fold 1's training set (case 0) is predicted, fold 0's (case 1) is not.
    assert!(cross_validate(&grid(1), &preds, &t, &[0, 1], 2, 0, 2).is_none());
}

#[test]
fn recorded_flights_fold_by_obstacle_set() {
    let (cases, _) = load_dir(std::path::Path::new("tests/data/hfs-flights")).expect("flights");
    let folds = assign_folds(&cases, 5, 0).expect("enough sets");
    // Repeats of one set never straddle folds.
    let mut fold_of_set: BTreeMap<String, usize> = BTreeMap::new();
    for (c, f) in cases.iter().zip(&folds) {
        let prev = fold_of_set.insert(obstacle_set_key(c), *f);
        assert!(prev.is_none_or(|p| p == *f), "{} in folds {prev:?} and {f}", c.id);
    }
    // Sets are dealt round-robin: fold sizes in sets differ by at most one.
    let mut sets_per_fold = [0usize; 5];
    for f in fold_of_set.values() {
        sets_per_fold[*f] += 1;
    }
    let (lo, hi) = (sets_per_fold.iter().min(), sets_per_fold.iter().max());
    assert!(hi.zip(lo).is_some_and(|(h, l)| h - l <= 1), "{sets_per_fold:?}");
    assert!(fold_of_set.len() < cases.len(), "the recorded flights hold repeats");
    // Deterministic per seed, different across seeds.
    assert_eq!(assign_folds(&cases, 5, 0), Some(folds.clone()));
    assert_ne!(assign_folds(&cases, 5, 1), Some(folds));
    assert!(assign_folds(&cases, 1, 0).is_none());
    assert!(assign_folds(&cases[..3], 5, 0).is_none());
}

#[test]
fn grids_hold_the_shipped_defaults() {
    let paper = default_grid("paper").expect("paper grid");
    assert!(
        paper
            .iter()
            .any(|g| g.motion == MotionModel::Paper(PaperParams::default()))
    );
    let px4 = default_grid("px4").expect("px4 grid");
    assert!(px4.iter().any(|g| g.motion == MotionModel::Px4(Px4Params::default())));
    assert!(default_grid("nope").is_none());
}

proptest! {
    /// Whatever the predictions, the pooled figure covers every predicted case exactly once and is the
    /// size-weighted mean of the folds' held-out errors.
    #[test]
    fn pooled_figure_covers_each_case_once(
        reals in prop::collection::vec(0.0f64..5.0, 6..20),
        offsets in prop::collection::vec(-2.0f64..2.0, 3),
        k in 2usize..4,
    ) {
        let t: Vec<Truth> = reals.iter().map(|r| Truth { real: *r, tier: "A".into() }).collect();
        let preds: Vec<Vec<Option<f64>>> = offsets
            .iter()
            .enumerate()
            .map(|(g, o)| reals.iter().enumerate().map(|(i, r)| Some(r + o * ((i + g) % 3) as f64)).collect())
            .collect();
        let folds: Vec<usize> = (0..reals.len()).map(|i| i % k).collect();
        let r = cross_validate(&grid(3), &preds, &t, &folds, k, 0, reals.len()).expect("report");
        prop_assert_eq!(r.cross_validated.n, reals.len());
        prop_assert_eq!(r.folds.iter().map(|f| f.n_held_out).sum::<usize>(), reals.len());
        let weighted: f64 = r.folds.iter().map(|f| f.held_out_figure.mae.unwrap_or(0.0) * f.n_held_out as f64).sum();
        let pooled = r.cross_validated.mae.unwrap_or(f64::NAN);
        prop_assert!((pooled - weighted / reals.len() as f64).abs() < 1e-9);
    }
}
