use super::*;
use crate::campaign::report::verdicts::verdicts;
use crate::campaign::store::journal::test_record;

/// A flight of `candidate` with two boxes placed by its index (far apart between candidates), flown to `d`
/// metres in `time_s`; its trajectory is not on disk.
fn flight(candidate: u64, attempt: u32, d: f64, time_s: f64) -> FlightRecord {
    let x = candidate as f64 * 30.0;
    let mut r = FlightRecord {
        attempt,
        obstacles: vec![
            Obstacle::new(4.0, 4.0, 20.0, x, 10.0, 0.0),
            Obstacle::new(4.0, 4.0, 20.0, x, 30.0, 0.0),
        ],
        trajectory: format!("flights/c{candidate}_{attempt}.csv").into(),
        ..test_record(candidate, d, Some(d))
    };
    r.flown.flight_time_s = time_s;
    r
}

fn aimed(records: &[FlightRecord]) -> (Vec<TestVerdict>, SuiteExpectation) {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut tests = verdicts(records, 3);
    let suite = aim(dir.path(), records, &mut tests);
    (tests.into_iter().map(|(t, _)| t).collect(), suite)
}

#[test]
fn tests_rank_by_expected_score_and_write_only_those_expected_to_earn() {
    // 3 was predicted to pass.
    let predicted_pass = |mut r: FlightRecord| {
        r.prediction.as_mut().expect("predicted").min_distance = 2.0;
        r
    };
    let records = [
        // 1: two 2-point flights in 2 minutes; 2: one 5-point flight in 1 minute; 3: one 1-point flight of
        // five; 4: never failed.
        flight(1, 0, 0.5, 120.0),
        flight(1, 1, 0.6, 120.0),
        flight(2, 0, 0.1, 60.0),
        predicted_pass(flight(3, 0, 1.4, 60.0)),
        predicted_pass(flight(3, 1, 2.0, 60.0)),
        predicted_pass(flight(3, 2, 2.1, 60.0)),
        predicted_pass(flight(3, 3, 2.2, 60.0)),
        predicted_pass(flight(3, 4, 2.3, 60.0)),
        flight(4, 0, 3.0, 60.0),
    ];
    let (tests, suite) = aimed(&records);
    let order: Vec<(u64, bool)> = tests.iter().map(|t| (t.candidate.0, t.confirmed)).collect();
    assert_eq!(order, [(2, true), (1, true), (3, false)], "{tests:#?}");
    assert_eq!(
        tests[0].similar_chance,
        Some(0.0),
        "the best test cannot copy a better one"
    );
    assert_eq!(tests[2].similar_chance, None, "not written");
    let e: Vec<TestExpectation> = tests.iter().filter_map(|t| t.expected).collect();
    assert!(e[0].score > e[1].score && e[1].score > e[2].score);
    assert!((e[1].minutes - 2.0).abs() < 1e-12);
    for x in &e {
        assert!(x.score_low <= x.score && x.score <= x.score_high, "{x:?}");
    }
    assert_eq!(suite.tests, 2);
    assert!((suite.total_score - (e[0].score + e[1].score)).abs() < 1e-12);
    assert_eq!(suite.sim_pen, 1.0, "no trajectory on disk: nothing to compare");
    assert_eq!(suite.final_score, suite.total_score);
    assert!(suite.final_low <= suite.final_score && suite.final_score <= suite.final_high);
    // The tests scatter independently: the suite's interval is narrower than its tests' bounds summed.
    let sd = (e[0].score_sd.powi(2) + e[1].score_sd.powi(2)).sqrt();
    assert!(
        (suite.total_high - suite.total_score - Z80 * sd).abs() < 1e-9,
        "{suite:?}"
    );
    assert!(suite.total_high - suite.total_low < e[0].score_high - e[0].score_low + e[1].score_high - e[1].score_low);
}

#[test]
fn a_test_flying_the_same_path_as_a_better_one_is_set_aside_with_its_distance() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = crate::model::Trajectory::new(
        (0..80)
            .map(|i| crate::model::Sample {
                t_s: f64::from(i) * 0.5,
                x: f64::from(i),
                y: 0.0,
                z: 10.0,
                r: None,
            })
            .collect(),
    );
    std::fs::create_dir_all(dir.path().join("flights")).expect("flights/");
    let records = [
        flight(1, 0, 0.5, 60.0),
        flight(1, 1, 0.6, 60.0),
        flight(2, 0, 0.7, 60.0),
        flight(2, 1, 0.8, 60.0),
    ];
    for r in &records {
        std::fs::write(dir.path().join(&r.trajectory), path.to_csv()).expect("csv");
    }
    let mut tests = verdicts(&records, 3);
    let suite = aim(dir.path(), &records, &mut tests);
    let (best, copy) = (&tests[0].0, &tests[1].0);
    assert_eq!(
        (best.candidate.0, best.confirmed, best.similar_chance),
        (1, true, Some(0.0))
    );
    assert!(!copy.confirmed && copy.similar_chance.is_none(), "{copy:?}");
    assert_eq!(copy.near_duplicate_of.as_deref(), Some("test_0.yaml"));
    assert!(copy.near_duplicate_dtw_m.is_some_and(|d| d < 1e-9), "{copy:?}");
    assert_eq!((suite.tests, suite.near_duplicates, suite.sim_pen), (1, 1, 1.0));
}

#[test]
fn the_calibrated_prediction_and_neighbours_move_the_estimate() {
    let alone = [flight(1, 0, 1.2, 60.0)];
    let (tests, _) = aimed(&alone);
    let base = tests[0].expected.expect("estimated").points;
    assert_eq!(base.mean, 1.0, "no calibration, no neighbour: its own flight alone");
    // A neighbour overlapping it (same place) flew to 0.1 m: the estimate rises.
    let mut near = flight(1, 0, 0.1, 60.0);
    near.candidate = CandidateId(9);
    let (tests, _) = aimed(&[alone[0].clone(), near]);
    let t = tests.iter().find(|t| t.candidate.0 == 1).expect("test 1");
    assert!(t.expected.expect("estimated").points.mean > base.mean);
    // Three other tests whose flights came 2 m further than predicted: the prior expects a pass.
    let mut records = vec![alone[0].clone()];
    for c in 2..5 {
        let mut r = flight(c, 0, 3.0, 60.0);
        r.prediction.as_mut().expect("predicted").min_distance = 1.0;
        records.push(r);
    }
    let (tests, _) = aimed(&records);
    let t = tests.iter().find(|t| t.candidate.0 == 1).expect("test 1");
    assert!(t.expected.expect("estimated").points.mean < base.mean);
}
