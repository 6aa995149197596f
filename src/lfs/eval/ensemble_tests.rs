use std::path::Path;

use proptest::prelude::*;

use super::*;
use crate::lfs::motion::PaperParams;
use crate::lfs::sim::simulate;
use crate::model::TestCase;

fn two_box_test() -> TestCase {
    TestCase::load(Path::new("missions/mission2.yaml"))
        .unwrap()
        .with_obstacles(vec![
            Obstacle::new(10.0, 5.0, 20.0, 10.0, 20.0, 0.0),
            Obstacle::new(10.0, 5.0, 20.0, -10.0, 20.0, 0.0),
        ])
}

fn run(test: &TestCase, params: &EnsembleParams, n: usize, seed: u64, jobs: usize) -> Ensemble {
    let c = SimConfig::default();
    run_ensemble(&test.mission, &test.obstacles, &test.params, &c, params, n, seed, jobs).unwrap()
}

#[test]
fn without_perturbation_every_member_is_the_plain_simulation_bit_for_bit() {
    let test = two_box_test();
    let plain = simulate(&test, &SimConfig::default()).unwrap();
    let want = plain.distance.unwrap().min_distance;
    let e = run(&test, &EnsembleParams::none(), 3, 7, 2);
    assert!(e.fork_cycle > 0, "members share the takeoff");
    for d in &e.member_min_distances {
        assert_eq!(d.to_bits(), want.to_bits());
    }
}

#[test]
fn same_seed_same_members_whatever_the_threads_and_other_seeds_differ() {
    let test = two_box_test();
    let p = EnsembleParams::default();
    let a = run(&test, &p, 4, 11, 1);
    let b = run(&test, &p, 4, 11, 2);
    assert_eq!(a, b);
    // Member k does not depend on how many members there are.
    let c = run(&test, &p, 2, 11, 1);
    assert_eq!(c.member_min_distances[..], a.member_min_distances[..2]);
    let spread = a.member_min_distances.iter().any(|d| *d != a.member_min_distances[0]);
    assert!(spread, "perturbed members should differ: {:?}", a.member_min_distances);
}

#[test]
fn bad_member_counts_and_obstacle_free_tests_are_refused() {
    let test = two_box_test();
    let c = SimConfig::default();
    let p = EnsembleParams::default();
    let e = |n| run_ensemble(&test.mission, &test.obstacles, &test.params, &c, &p, n, 0, 1);
    assert_eq!(e(0), Err(EnsembleError::Members(0)));
    assert_eq!(e(MAX_MEMBERS + 1), Err(EnsembleError::Members(MAX_MEMBERS + 1)));
    let free = run_ensemble(&test.mission, &[], &test.params, &c, &p, 2, 0, 1);
    assert_eq!(free, Err(EnsembleError::NoObstacles));
    let bad = EnsembleParams { speed_rel: -0.1, ..p };
    let r = run_ensemble(&test.mission, &test.obstacles, &test.params, &c, &bad, 2, 0, 1);
    assert!(matches!(r, Err(EnsembleError::Sim(SimError::Setting(m))) if m.contains("speed_rel")));
}

#[test]
fn p_fail_is_the_beta_posterior_mean() {
    let p = EnsembleParams {
        prior_fail: 1.0,
        prior_pass: 3.0,
        ..EnsembleParams::none()
    };
    // (2 + 1) / (8 + 4)
    assert_eq!(p.p_fail(2, 8), Some(0.25));
    assert_eq!(EnsembleParams::none().p_fail(3, 4), Some(0.75));
    assert_eq!(EnsembleParams::none().p_fail(0, 0), None);
    let e = Ensemble {
        member_min_distances: vec![0.5, 1.49, 1.5, 3.0],
        fork_cycle: 0,
    };
    assert_eq!(e.p_fail(&EnsembleParams::none()), Some(0.5));
    assert_eq!(e.p_fail(&p), Some(3.0 / 8.0));
}

#[test]
fn expected_points_weigh_p_fail_by_the_failing_members_points() {
    // Members at 0.1 m (5 points) and 1.2 m (1 point) fail, two pass: p_fail 0.5, 3 points per failure.
    let e = Ensemble {
        member_min_distances: vec![0.1, 1.2, 1.5, 3.0],
        fork_cycle: 0,
    };
    assert_eq!(e.expected_points(&EnsembleParams::none()), Some(1.5));
    // No failing member: only the prior fails, each failure worth the least a failure earns.
    let passing = Ensemble {
        member_min_distances: vec![2.0, 3.0],
        fork_cycle: 0,
    };
    let prior = EnsembleParams {
        prior_fail: 2.0,
        ..EnsembleParams::none()
    };
    assert_eq!(passing.expected_points(&prior), Some(0.5));
    assert_eq!(passing.expected_points(&EnsembleParams::none()), Some(0.0));
}

#[test]
fn a_longer_delay_set_in_flight_does_not_stop_the_vehicle() {
    let test = two_box_test();
    let mut w = World::new(&test, SimConfig::default()).unwrap();
    // Cruising: the last command moved it horizontally.
    while w.vehicle.velocity_enu.xy().norm() < 1.0 {
        assert!(step(&mut w, 0.1).is_none());
    }
    let before = w.vehicle.position_enu;
    let slower = PaperParams {
        delay_ticks: 3,
        ..PaperParams::default()
    };
    w.set_motion(MotionModel::Paper(slower)).unwrap();
    step(&mut w, 0.1);
    assert!(
        (w.vehicle.position_enu - before).norm() > 0.05,
        "held still after the delay change"
    );
    let px4 = MotionModel::by_name("px4").unwrap();
    assert!(w.set_motion(px4).is_err());
}

proptest! {
    #[test]
    fn draws_stay_within_their_scales(seed in any::<u64>(), k in 0u64..1000, ph in 0.0..1.0f64,
                                      s in 0.0..0.5f64, pos in 0.0..1.0f64, yaw in 0.0..45.0f64, j in 0usize..4) {
        let params = EnsembleParams { phase_ticks: ph, delay_jitter_ticks: j, speed_rel: s, obstacle_pos_m: pos,
                                      obstacle_yaw_deg: yaw, ..EnsembleParams::none() };
        let base = PaperParams::default();
        let boxes = two_box_test().obstacles;
        let d = draw_member(&params, MotionModel::Paper(base), &boxes, seed, k);
        prop_assert_eq!(&d, &draw_member(&params, MotionModel::Paper(base), &boxes, seed, k));
        prop_assert!(d.phase >= 0.0 && d.phase <= ph);
        let MotionModel::Paper(m) = d.motion else { return Err(TestCaseError::fail("kind changed")) };
        prop_assert!((m.max_speed_m_s / base.max_speed_m_s - 1.0).abs() <= s + 1e-12);
        prop_assert!(m.delay_ticks.abs_diff(base.delay_ticks) <= j);
        for (a, b) in d.obstacles.unwrap_or_else(|| boxes.clone()).iter().zip(&boxes) {
            prop_assert!((a.position.x - b.position.x).abs() <= pos + 1e-12);
            prop_assert!((a.position.y - b.position.y).abs() <= pos + 1e-12);
            prop_assert!((a.position.r - b.position.r).abs() <= yaw + 1e-12);
        }
    }
}
