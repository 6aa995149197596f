use super::*;
use crate::model::competition::HALF_VEHICLE_WIDTH_M;

#[test]
fn spearman_known_answers() {
    let a = [1.0, 2.0, 3.0, 4.0];
    assert_eq!(spearman(&a, &[10.0, 20.0, 30.0, 40.0]), Some(1.0));
    assert_eq!(spearman(&a, &[4.0, 3.0, 2.0, 1.0]), Some(-1.0));
    // Ties get averaged ranks: ranks of b are (1.5, 1.5, 3, 4).
    let s = spearman(&a, &[1.0, 1.0, 2.0, 3.0]).unwrap();
    assert!((s - 0.948_683).abs() < 1e-5, "{s}");
    assert_eq!(spearman(&a, &[1.0, 1.0, 1.0, 1.0]), None);
    assert_eq!(spearman(&[1.0], &[1.0]), None);
}

#[test]
fn aggregates_by_hand() {
    // (predicted, real): TP, FP, FN, TN.
    let a = aggregate(&[(1.0, 1.2), (1.0, 3.0), (2.0, 0.5), (4.0, 5.0)]);
    assert_eq!(a.n, 4);
    assert!((a.mae.unwrap() - (0.2 + 2.0 + 1.5 + 1.0) / 4.0).abs() < 1e-12);
    assert_eq!((a.precision, a.recall), (Some(0.5), Some(0.5)));
    let none = aggregate(&[]);
    assert_eq!((none.n, none.mae, none.precision), (0, None, None));
}

#[test]
fn loads_every_tier_of_the_recorded_flights() {
    let dir = std::path::Path::new("tests/data/hfs-flights");
    let (cases, skipped) = load_dir(dir).unwrap();
    assert_eq!(cases.len() + skipped.len(), 130);
    assert_eq!(skipped.len(), 3, "{skipped:?}");
    let b = cases.iter().find(|c| c.tier == "B").unwrap();
    assert_eq!(b.definition_offset_m, HALF_VEHICLE_WIDTH_M);
    let c = cases.iter().find(|c| c.id == "case_zhekai_002").unwrap();
    assert_eq!(c.mission_name, "mission2");
    assert_eq!(c.obstacles.len(), 2);
    assert!((c.real_m - 3.6818).abs() < 1e-12);
    assert_eq!(c.mission.flight_path().len(), 3);
    assert!(c.params.iter().any(|p| p.name == "NAV_ACC_RAD" && p.value == 0.5));
    assert!(cases.iter().filter(|c| c.repeat_group.is_some()).count() > 70);
}

#[test]
fn bad_files_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("x.json");
    for text in [
        "not json",
        "{}",
        r#"{"id": "a", "tier": "A", "mission": {"waypoints": []}, "obstacles": []}"#,
    ] {
        std::fs::write(&p, text).unwrap();
        assert!(load_flight(&p).is_err(), "{text}");
    }
    assert!(load_dir(&dir.path().join("missing")).is_err());
}

#[test]
fn evaluates_a_real_case_end_to_end() {
    let flight = std::path::Path::new("tests/data/hfs-flights/case_sefbk_001.json");
    let case = load_flight(flight).unwrap().unwrap();
    let report = evaluate(std::slice::from_ref(&case), vec![], &SimConfig::default(), 2);
    let r = &report.cases[0];
    assert_eq!(r.status, Some(SimStatus::Landed));
    let p = r.predicted.unwrap();
    assert!((0.0..20.0).contains(&p), "{p}");
    assert_eq!(report.mae, r.abs_error);
    assert_eq!(report.tiers["A"].n, 1);
}

#[test]
fn an_unperturbed_ensemble_agrees_with_the_point_prediction() {
    let flight = std::path::Path::new("tests/data/hfs-flights/case_sefbk_001.json");
    let case = load_flight(flight).unwrap().unwrap();
    let spec = EnsembleSpec {
        params: EnsembleParams::none(),
        n: 2,
        seed: 0,
    };
    let config = SimConfig::default();
    let r = evaluate_case_with(&case, &config, Some(&spec));
    let below = r.predicted.unwrap() < FAIL_BELOW_M;
    assert_eq!(r.p_fail, Some(if below { 1.0 } else { 0.0 }));
    // Two cases, one a fail and one a pass by the record: AUC and Brier from the two p_fail.
    let mut pass = case.clone();
    pass.real_m = 9.0;
    let mut fail = case;
    fail.real_m = 0.5;
    let report = evaluate_with(&[fail, pass], vec![], &config, Some(&spec), 1);
    assert_eq!(report.auc, Some(0.5), "equal p_fail ties");
    assert_eq!(report.brier, Some(0.5), "one of two outcomes missed with certainty");
    assert_eq!(report.tiers["A"].brier, report.brier);
}

#[test]
fn probability_scores_of_pairs() {
    let (auc, brier) = probability_scores(&[(0.9, 1.0), (0.2, 2.0), (0.4, 3.0)]);
    assert_eq!(auc, Some(1.0));
    // (0.1^2 + 0.2^2 + 0.4^2) / 3
    assert!((brier.unwrap() - 0.21 / 3.0).abs() < 1e-15);
}

#[test]
fn folds_keep_repeats_of_one_obstacle_set_together() {
    let (cases, _) = load_dir(std::path::Path::new("tests/data/hfs-flights")).unwrap();
    let mut fold_of_group = std::collections::BTreeMap::new();
    let mut sizes = [0usize; 5];
    for c in &cases {
        let f = fold_of(c, 5);
        sizes[f] += 1;
        if let Some(g) = &c.repeat_group {
            assert_eq!(*fold_of_group.entry(g.clone()).or_insert(f), f, "{g} straddles folds");
        }
    }
    assert!(!fold_of_group.is_empty());
    assert!(sizes.iter().all(|s| *s >= 10), "unbalanced folds {sizes:?}");
}
