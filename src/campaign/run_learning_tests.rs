//! Tests of the learning campaign (calibration, adapted draws, children of failing flights, the diversity
//! guard) with the scripted LFS and vehicles of `run_tests.rs`.

use super::*;

#[test]
fn a_learning_campaign_calibrates_on_its_flights_adapts_its_draws_and_seeds_the_next_one() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let cfg = adapted(12);
    let r = run_scripted(&cfg, dir.path(), &flown);
    assert_eq!(r.suite.flown, 12);
    let learnt = r.learning.as_ref().expect("a learning campaign reports what it learnt");
    assert!(learnt.rounds.len() >= crate::campaign::conductor::ROUNDS);
    // The scripted vehicle flies 0.2 m farther than predicted: the bias goes there, shrunk by the prior.
    let bias = learnt.calibration.bias_m();
    assert!((bias - 0.2 * 12.0 / 13.0).abs() < 1e-9, "{bias}");
    assert_eq!(learnt.rounds[0].bias_m, 0.0, "the first round knows nothing yet");
    // Calibrated predictions make the last quarter's error smaller than the first's.
    let (first, last) = (
        r.suite.lfs_error_first_quarter_m.unwrap(),
        r.suite.lfs_error_last_quarter_m.unwrap(),
    );
    assert!(last < first, "{first} -> {last}");
    // The draws moved towards the elites.
    assert!(!learnt.distribution.is_uniform());
    assert!(learnt.rounds[1].draw_means != [0.5; DIMS]);
    // After the first flights, candidates are also drawn around the closest ones, except while the failing
    // tests are less diverse than the floor (this vehicle fails in one place).
    assert_eq!(learnt.rounds[0].local_candidates, 0);
    for round in &learnt.rounds[1..] {
        // A box without a distinct child gives its draw to the histogram.
        assert!(
            round.local_candidates <= crate::campaign::plan::neighbours::CHILDREN,
            "{round:?}"
        );
        assert!((0.25..=0.85).contains(&round.local_flight_share), "{round:?}");
    }
    // Children once the first failures are in, no more than the round's own draws.
    let local: Vec<usize> = learnt.rounds.iter().map(|r| r.local_candidates).collect();
    assert!(local.iter().filter(|l| **l > 0).count() >= 2, "{local:?}");
    for r in &learnt.rounds {
        assert!(r.local_candidates <= r.candidates - r.local_candidates, "{r:?}");
    }
    // This vehicle fails along one line, yet the guard keeps the failing tests as diverse as the floor.
    let failing: Vec<Vec<crate::model::Obstacle>> = Journal::read(&dir.path().join("journal.jsonl"))
        .unwrap()
        .into_iter()
        .filter(|r| r.flown.min_distance.is_some_and(|d| d < 1.5))
        .map(|r| r.obstacles)
        .collect();
    let d = crate::judge::diversity(&failing);
    assert!(
        failing.len() >= 2 && d.is_some_and(|d| d >= cfg.learning.min_diversity),
        "{} failing, {d:?}",
        failing.len()
    );
    assert!(dir.path().join("learnt.json").is_file());
    // Every flight counts in the failure model, under each draw.
    assert_eq!(learnt.failure_counts.total.flights, 12);
    for row in &learnt.failure_counts.draws {
        assert_eq!(row.iter().map(|c| c.flights).sum::<u32>(), 12);
    }
    // Every flight is counted under the proposal that drew it.
    let (near, misses, other) = (
        learnt.drawn_near_failures,
        learnt.drawn_near_misses,
        learnt.drawn_elsewhere,
    );
    assert_eq!(near.flights + misses.flights + other.flights, 12);
    assert_eq!(
        near.failures + misses.failures + other.failures,
        learnt.failure_counts.total.failures
    );
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(md.contains("Where the flights failed"), "{md}");
    assert!(near.flights > 0, "{near:?}");
    let close = learnt.drawn_close;
    assert!(
        close.flights <= near.flights && close.failures <= near.failures,
        "{close:?} of {near:?}"
    );
    assert!(md.contains("Candidates drawn near failing flights failed"), "{md}");
    // Every test flown still obeys the rules.
    for rec in Journal::read(&dir.path().join("journal.jsonl")).unwrap() {
        let t = TestCase::load(&cfg.campaign.case)
            .unwrap()
            .with_obstacles(rec.obstacles);
        assert!(crate::rules::check(&t, &crate::model::Arena::default()).is_empty());
    }
    // The next campaign starts from it: the first round already uses the learnt bias.
    let next_dir = tempfile::tempdir().unwrap();
    let next_cfg = {
        let mut c = cfg.clone();
        c.campaign.prior = Some(dir.path().to_path_buf());
        c
    };
    let r2 = run_scripted(&next_cfg, next_dir.path(), &flown);
    let l2 = r2.learning.unwrap();
    assert!((l2.rounds[0].bias_m - bias).abs() < 1e-12);
    // The failure counts are this campaign's own.
    assert_eq!(l2.failure_counts.total.flights, 12);
    assert_eq!(
        l2.rounds[0].draw_means,
        std::array::from_fn(|d| learnt.distribution.mean(d))
    );
    // A missing prior is an error naming the file.
    let bad = {
        let mut c = cfg;
        c.campaign.prior = Some(next_dir.path().join("nowhere"));
        c
    };
    let e = run_campaign_with(
        &bad,
        tempfile::tempdir().unwrap().path(),
        &ScriptedLfs,
        vehicle(&flown, None),
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap_err();
    assert!(e.to_string().contains("learnt.json"), "{e}");
}

#[test]
fn children_come_no_closer_than_child_max_iou_and_never_held_below_max_iou() {
    use crate::campaign::plan::diversity_guard::child_max_iou;
    let mut cfg = config(10);
    assert_eq!(child_max_iou(&cfg), 0.5, "no --child-max-iou: max_iou");
    cfg.learning.child_max_iou = 0.75;
    assert_eq!(child_max_iou(&cfg), 0.75);
    cfg.learning.child_max_iou = 0.3;
    assert_eq!(child_max_iou(&cfg), 0.5);
}

#[test]
fn close_children_stay_within_child_max_iou_of_every_flown_test() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = {
        let mut c = adapted(24);
        c.learning.min_diversity = 0.0;
        c.learning.child_max_iou = 0.75;
        c
    };
    let r = run_scripted(&cfg, dir.path(), &Arc::new(Mutex::new(Vec::new())));
    let learnt = r.learning.expect("learnt");
    let tests: Vec<Vec<crate::geometry::Footprint>> = Journal::read(&dir.path().join("journal.jsonl"))
        .unwrap()
        .iter()
        .map(|r| r.obstacles.iter().map(crate::model::Obstacle::footprint).collect())
        .collect();
    let mut closest = 0.0_f64;
    for (i, a) in tests.iter().enumerate() {
        for b in &tests[..i] {
            closest = closest.max(crate::geometry::union_iou(a, b));
        }
    }
    assert!(closest <= 0.75 + 1e-9, "{closest}");
    let (close, near) = (learnt.drawn_close, learnt.drawn_near_failures);
    assert!(close.flights <= near.flights, "{close:?} of {near:?}");
    // With no diversity floor, this vehicle's one failing place gets close children.
    assert!(close.flights > 0 && closest > 0.5, "{close:?}, closest pair {closest}");
}

#[test]
fn a_vehicle_that_never_fails_gets_children_around_its_closest_flights() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = adapted(24);
    // Flies 1.5 m farther than the scripted LFS predicts: never below 1.5 m, often within 0.3 m of it.
    let vehicles: Vec<Box<dyn Vehicle>> = vec![Box::new(ScriptedVehicle {
        flown: Arc::new(Mutex::new(Vec::new())),
        stop_after: None,
        count: Arc::new(AtomicUsize::new(0)),
        extra_m: 1.5,
    })];
    let r = run_with(&cfg, dir.path(), vehicles).unwrap();
    assert_eq!((r.suite.flown, r.suite.failing), (24, 0));
    let learnt = r.learning.expect("learnt");
    let first = &learnt.rounds[0];
    assert!(!first.near_miss_parents && first.local_candidates == 0, "{first:?}");
    let later: Vec<_> = learnt.rounds[1..].iter().filter(|r| r.near_miss_parents).collect();
    assert!(!later.is_empty(), "{:?}", learnt.rounds);
    assert!(later.iter().all(|r| r.local_candidates > 0));
    let (near, misses, other) = (
        learnt.drawn_near_failures,
        learnt.drawn_near_misses,
        learnt.drawn_elsewhere,
    );
    assert_eq!(near.flights, 0, "no failure, no failure's child");
    assert!(misses.flights > 0, "{misses:?}");
    assert_eq!(misses.flights + other.flights, 24);
    let md = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(md.contains("near misses) |"), "{md}");
    let line = format!(
        "near the closest flights before the first failure, 0 of {}; the others 0 of {}.",
        misses.flights, other.flights
    );
    assert!(md.contains(&line), "{md}");
}

#[test]
fn below_the_diversity_floor_the_failures_still_get_children() {
    let dir = tempfile::tempdir().unwrap();
    // A floor no set of failures reaches: from the fourth failure on the failing tests are always below it.
    let cfg = {
        let mut c = adapted(40);
        c.learning.min_diversity = 0.999;
        c
    };
    let r = run_scripted(&cfg, dir.path(), &Arc::new(Mutex::new(Vec::new())));
    let learnt = r.learning.expect("learnt");
    assert!(
        r.suite.failed_once >= crate::campaign::learn::refit::MIN_FAILING_FOR_DIVERSITY,
        "{:?}",
        r.suite
    );
    // Below the floor the children go on: the guard admits those that do not lower the diversity, so the late
    // rounds still draw some.
    let late: Vec<usize> = learnt.rounds[4..].iter().map(|r| r.local_candidates).collect();
    assert!(late.iter().any(|&c| c > 0), "{:?}", learnt.rounds);
}
