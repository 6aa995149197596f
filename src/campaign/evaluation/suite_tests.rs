use super::*;
use crate::model::{Obstacle, Sample};

fn mission2() -> TestCase {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
    TestCase::load(&path).unwrap()
}

/// A flight from home (the origin) north along `y = east`, 10 m up, `secs` long, sampled every 0.1 s.
fn flight(east: f64, secs: f64) -> Trajectory {
    let n = (secs * 10.0) as usize;
    let home = Sample {
        t_s: 0.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
        r: Some(0.0),
    };
    let along = (1..=n).map(|i| {
        let t = i as f64 / 10.0;
        Sample {
            t_s: t,
            x: 50.0 * t / secs,
            y: east,
            z: 10.0,
            r: Some(0.0),
        }
    });
    Trajectory::new(std::iter::once(home).chain(along).collect())
}

fn flown(name: &str, boxes: Vec<Obstacle>, flights: Vec<Trajectory>) -> FlownTest {
    FlownTest {
        path: PathBuf::from(name),
        test: mission2().with_obstacles(boxes),
        flights: flights
            .into_iter()
            .enumerate()
            .map(|(k, f)| (PathBuf::from(format!("{name}-{k}.csv")), f))
            .collect(),
    }
}

/// A box whose west face is at `y = 1`: a flight along `y = east` passes `1 - east` metres away (x 20-30).
fn wall() -> Obstacle {
    Obstacle::new(10.0, 2.0, 20.0, 25.0, 2.0, 0.0)
}

/// A test beside the wall with runs 0.1 m (5 points) and 0.9 m (2 points) from it, 60 s each.
fn five_then_two(name: &str) -> FlownTest {
    let runs = [0.1, 0.9].map(|d| flight(1.0 - d - 0.125, 60.0));
    flown(name, vec![wall()], runs.to_vec())
}

#[test]
fn scores_mean_points_and_penalises_a_copied_trajectory() {
    // Test a: runs 0.9 m (2 points) and 0.1 m (5 points) from the box, 60 s each.
    let a = five_then_two("a.yaml");
    // Test b: the same flights again (a copy of a's trajectory).
    let b = five_then_two("b.yaml");
    // Test c: far away (0 points), a different path.
    let c = flown("c.yaml", vec![wall()], vec![flight(-30.0, 30.0), flight(-30.0, 30.0)]);
    let (e, averages) = evaluate_suite(&[a, b, c], Judge::E2026, 50.0).unwrap();
    assert_eq!(averages.iter().filter(|a| a.is_some()).count(), 3);
    let t = &e.tests[0];
    assert_eq!(t.runs.iter().map(|r| r.points).collect::<Vec<_>>(), vec![5, 2]);
    assert!((t.mean_points - 3.5).abs() < 1e-12);
    // 3.5 points x 10 / (1 obstacle x 1 minute).
    assert!((t.score - 35.0).abs() < 1e-6, "{}", t.score);
    assert_eq!(e.tests[1].similar_to, Some(0));
    assert_eq!(e.tests[2].similar_to, None);
    assert_eq!((e.similar_tests, e.evaluated), (1, 3));
    assert!((e.sim_pen - 2.0 / 3.0).abs() < 1e-12);
    assert!((e.final_score - e.total_score * 2.0 / 3.0).abs() < 1e-9);
    assert_eq!(e.pairs.len(), 3);
    assert!(e.pairs[0].dtw < 1e-9 && e.pairs[0].similar);
    assert!(e.pairs[1].dtw > 50.0 && !e.pairs[1].similar);
    // 2025: a and b failed, with the same footprints (diversity 0).
    assert_eq!(e.figures_2025.failing, 2);
    assert_eq!(e.figures_2025.diversity, Some(0.0));
}

#[test]
fn a_test_without_flights_is_not_evaluated_and_has_no_average() {
    let a = flown("a.yaml", vec![wall()], vec![flight(0.5, 60.0)]);
    let none = flown("n.yaml", vec![wall()], vec![]);
    let (e, averages) = evaluate_suite(&[a, none], Judge::E2026, 50.0).unwrap();
    assert_eq!(e.evaluated, 1);
    assert!(averages[1].is_none());
    assert!(e.pairs.is_empty());
    assert_eq!(e.tests[1].score, 0.0);
    assert_eq!(e.sim_pen, 1.0);
    // Nothing failed: a failure score of +0, printed "0.000", not "-0.000".
    let far = flown("far.yaml", vec![wall()], vec![flight(-30.0, 30.0)]);
    let (e, _) = evaluate_suite(&[far], Judge::E2026, 50.0).unwrap();
    assert_eq!(e.figures_2025.failing, 0);
    assert!(
        e.figures_2025.failure_score.is_sign_positive(),
        "{}",
        e.figures_2025.failure_score
    );
}

#[test]
fn a_test_without_obstacles_is_an_error_naming_it() {
    let a = flown("bare.yaml", vec![], vec![flight(0.5, 60.0)]);
    let err = evaluate_suite(&[a], Judge::E2026, 50.0).unwrap_err().to_string();
    assert!(err.contains("bare.yaml") && err.contains("obstacles"), "{err}");
}

#[test]
fn a_run_over_a_low_box_earns_5_points_in_2026_and_the_report_says_it_was_above_the_top() {
    // An 8.8 m box under the 10 m flight: the path crosses it 1.2 m above its top.
    let low = Obstacle::new(10.0, 4.0, 8.8, 25.0, 0.0, 0.0);
    let a = flown("a.yaml", vec![low], vec![flight(0.0, 60.0), flight(0.0, 60.0)]);
    let (e, _) = evaluate_suite(std::slice::from_ref(&a), Judge::E2026, 50.0).unwrap();
    let over = e.tests[0].runs[0].above_top.expect("above the top");
    assert_eq!(over.obstacle, 0);
    assert!((over.height_m - 1.2).abs() < 1e-9, "{}", over.height_m);
    assert_eq!(e.tests[0].runs[0].points, 5);
    let md = super::super::report::markdown(&e, &Default::default());
    assert!(md.contains("(5, above obstacle 0)"), "{md}");
    assert!(
        md.contains("2 run(s) came closest to a box above its top (the lowest 1.20 m above)"),
        "{md}"
    );
    assert!(md.contains("horizontal only"), "{md}");
    // The 2025 edition scores the same runs by their 1.2 m height gap: 1 point each.
    let (e, _) = evaluate_suite(&[a], Judge::E2025, 50.0).unwrap();
    assert_eq!(e.tests[0].runs[1].points, 1);
    assert!(super::super::report::markdown(&e, &Default::default()).contains("height gap only straight over a box"));
    // A flight beside a box taller than it: nothing above a top, and the report says nothing of it.
    let beside = flown("b.yaml", vec![wall()], vec![flight(-0.5, 60.0)]);
    let (e, _) = evaluate_suite(&[beside], Judge::E2026, 50.0).unwrap();
    assert!(e.tests[0].runs[0].above_top.is_none());
    assert!(!super::super::report::markdown(&e, &Default::default()).contains("above its top"));
}

#[test]
fn the_total_has_a_standard_error_from_the_runs_scatter_and_none_from_single_runs() {
    // Runs of 5 and 2 points over 60 s (one box): score 35, the points' sample sd 2.12, so the score's
    // standard error is 10 (the score per point) x 2.12 / √2 = 15.
    let a = five_then_two("a.yaml");
    // Two passes: no scatter.
    let c = flown("c.yaml", vec![wall()], vec![flight(-30.0, 30.0), flight(-30.0, 30.0)]);
    let (e, _) = evaluate_suite(&[a.clone(), c], Judge::E2026, 50.0).unwrap();
    let sd = e.tests[0].score_sd.expect("two runs");
    assert!((sd - 15.0).abs() < 1e-6, "{sd}");
    assert_eq!(e.tests[1].score_sd, Some(0.0));
    assert!((e.total_score_sd.unwrap() - 15.0).abs() < 1e-6);
    let md = super::super::report::markdown(&e, &Default::default());
    assert!(
        md.contains("| total score | 35.000 (sd 15.000 from the runs' own scatter) |"),
        "{md}"
    );
    // One run of a test: no standard error for it, nor for the total.
    let one = flown("o.yaml", vec![wall()], vec![flight(0.5, 60.0)]);
    let (e, _) = evaluate_suite(&[a, one], Judge::E2026, 50.0).unwrap();
    assert_eq!((e.tests[1].score_sd, e.total_score_sd), (None, None));
    assert!(super::super::report::markdown(&e, &Default::default()).contains("| total score | "));
}
