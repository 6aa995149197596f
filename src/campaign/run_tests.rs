//! Campaign pipeline tests with a scripted screener and scripted vehicles (the real LFS and the mock
//! autopilot are exercised by the integration tests).

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use crate::campaign::journal::Journal;
use crate::campaign::pool::{Flown, Vehicle, VehicleError};
use crate::campaign::run::{CampaignConfig, CampaignError, Progress, Screener, run_campaign};
use crate::generator::GeneratorConfig;
use crate::generator::adaptive::DIMS;
use crate::model::TestCase;

/// Predicts obstacle 1's centre y minus 20 as the distance: deterministic and spread out.
struct ScriptedLfs;

impl Screener for ScriptedLfs {
    fn screen(&self, test: &TestCase) -> (f64, f64, String) {
        ((test.obstacles[0].position.y - 20.0).abs() / 2.0, 40.0, "landed".into())
    }
}

/// Flies by writing a two-sample CSV; the flown distance is the prediction plus `extra_m` (0.2 m unless
/// told). Cancels the campaign after `stop_after` flights (a "kill").
struct ScriptedVehicle {
    flown: Arc<Mutex<Vec<f64>>>,
    stop_after: Option<usize>,
    count: Arc<AtomicUsize>,
    extra_m: f64,
}

impl Vehicle for ScriptedVehicle {
    fn name(&self) -> String {
        "scripted".into()
    }
    fn fly(&mut self, test: &TestCase, csv: &Path, cancel: &AtomicBool) -> Result<Flown, VehicleError> {
        let y = test.obstacles[0].position.y;
        std::fs::write(csv, "timestamp,x,y,z,r\n0,0,0,0,\n1000000,0,10,10,\n").unwrap();
        self.flown.lock().unwrap().push(y);
        let n = self.count.fetch_add(1, Ordering::SeqCst) + 1;
        if self.stop_after.is_some_and(|k| n >= k) {
            cancel.store(true, Ordering::SeqCst);
        }
        let d = (y - 20.0).abs() / 2.0 + self.extra_m;
        Ok(landed(d))
    }
}

/// A 40 s flight that landed `d` metres from the boxes.
fn landed(d: f64) -> Flown {
    Flown {
        status: "landed".into(),
        min_distance: Some(d),
        min_distance_raw: Some(d),
        flight_time_s: 40.0,
        warnings: Vec::new(),
        reason: None,
    }
}

struct Quiet;
impl Progress for Quiet {
    fn stage(&self, _: &str, _: usize) {}
    fn tick(&self, _: usize) {}
    fn note(&self, _: &str) {}
}

fn config(budget: usize) -> CampaignConfig {
    CampaignConfig {
        judge: crate::judge::Judge::default(),
        anchor_at_vehicle_home: false,
        case: Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml"),
        seed: 3,
        budget,
        candidates: 60,
        threshold_m: 5.0,
        max_iou: 0.5,
        generator: GeneratorConfig::default(),
        old_spelling: false,
        hfs: vec!["scripted".into()],
        mode: "avoidance".into(),
        motion: "px4".into(),
        mock_speed: 20.0,
        mock_lockstep: true,
        mock_latency_ms: crate::campaign::run::DEFAULT_MOCK_LATENCY_MS,
        screen: true,
        hfs_time_scale: None,
        flight_timeout_s: 500.0,
        ensemble: 0,
        learn: false,
        adapt: false,
        prior: None,
        min_diversity: 0.8,
        child_max_iou: None,
    }
}

/// `cfg`'s campaign in `dir` with the scripted LFS and vehicles, run to its end.
fn run_scripted(cfg: &CampaignConfig, dir: &Path, flown: &Arc<Mutex<Vec<f64>>>) -> crate::campaign::run::Report {
    run_campaign(
        cfg,
        dir,
        &ScriptedLfs,
        vehicle(flown, None),
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap()
}

fn vehicle(flown: &Arc<Mutex<Vec<f64>>>, stop_after: Option<usize>) -> Vec<Box<dyn Vehicle>> {
    let count = Arc::new(AtomicUsize::new(0));
    vec![Box::new(ScriptedVehicle {
        flown: flown.clone(),
        stop_after,
        count,
        extra_m: 0.2,
    })]
}

#[test]
fn a_campaign_flies_the_budget_and_reports_failing_tests_best_first() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let r = run_campaign(
        &config(8),
        dir.path(),
        &ScriptedLfs,
        vehicle(&flown, None),
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(r.suite.flown, 8);
    assert_eq!(flown.lock().unwrap().len(), 8);
    // Flights went most-severe first.
    let predicted: Vec<f64> = r.flights.iter().map(|f| f.predicted_min_distance).collect();
    assert!(predicted.windows(2).all(|w| w[0] <= w[1]), "{predicted:?}");
    // Reported tests are exactly the flights below 1.5 m, best first, as valid YAML with their CSVs.
    let failing: Vec<f64> = r
        .flights
        .iter()
        .filter_map(|f| f.min_distance.filter(|d| *d < 1.5))
        .collect();
    assert_eq!(r.suite.failing, failing.len());
    assert!(r.suite.distinct_failing <= r.suite.failing);
    assert_eq!(r.suite.distinct_failing == 0, r.suite.failing == 0);
    let mut last = 0.0;
    for i in 0..r.suite.failing {
        let t = TestCase::load(&dir.path().join(format!("test_{i}.yaml"))).unwrap();
        assert!(crate::rules::check(&t, &crate::model::Arena::default()).is_empty());
        assert!(dir.path().join(format!("test_{i}.csv")).is_file());
        let svg = std::fs::read_to_string(dir.path().join(format!("test_{i}.svg"))).unwrap();
        assert!(svg.starts_with("<svg") || svg.starts_with("<?xml"), "a plot per test");
        let f = r
            .flights
            .iter()
            .find(|f| f.reported_as.as_deref() == Some(&format!("test_{i}.yaml")))
            .unwrap();
        assert!(f.min_distance.unwrap() >= last);
        last = f.min_distance.unwrap();
    }
    assert!(!dir.path().join(format!("test_{}.yaml", r.suite.failing)).exists());
    for f in [
        "report.json",
        "report.md",
        "journal.jsonl",
        "campaign.json",
        "screening.json",
    ] {
        assert!(dir.path().join(f).is_file(), "{f}");
    }
    assert_eq!(
        r.suite.lfs_precision,
        Some(1.0).filter(|_| r.flights.iter().any(|f| f.predicted_min_distance < 1.5))
    );
}

#[test]
fn killed_and_resumed_campaign_flies_nothing_twice_and_respects_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let cancel = AtomicBool::new(false);
    let first = run_campaign(
        &config(10),
        dir.path(),
        &ScriptedLfs,
        vehicle(&flown, Some(4)),
        &Quiet,
        &cancel,
    );
    assert_eq!(first.unwrap().suite.flown, 4);
    assert_eq!(Journal::read(&dir.path().join("journal.jsonl")).unwrap().len(), 4);
    let second = run_campaign(
        &config(10),
        dir.path(),
        &ScriptedLfs,
        vehicle(&flown, None),
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(second.suite.flown, 10);
    let all = flown.lock().unwrap().clone();
    assert_eq!(all.len(), 10);
    let mut dedup = all.clone();
    dedup.sort_by(f64::total_cmp);
    dedup.dedup();
    assert_eq!(dedup.len(), 10, "a test was flown twice: {all:?}");
    // A third run has nothing left to fly.
    let third = run_campaign(
        &config(10),
        dir.path(),
        &ScriptedLfs,
        vehicle(&flown, None),
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!((third.suite.flown, flown.lock().unwrap().len()), (10, 10));
}

#[test]
fn bad_settings_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let quiet = AtomicBool::new(false);
    let e = run_campaign(
        &config(0),
        dir.path(),
        &ScriptedLfs,
        vehicle(&flown, None),
        &Quiet,
        &quiet,
    )
    .unwrap_err();
    assert!(matches!(e, CampaignError::Config(_)), "{e}");
    let mut bad = config(3);
    bad.case = "missions/does-not-exist.yaml".into();
    let e = run_campaign(&bad, dir.path(), &ScriptedLfs, vehicle(&flown, None), &Quiet, &quiet).unwrap_err();
    assert!(e.to_string().contains("does-not-exist.yaml"), "{e}");
}

/// The scripted screener with an ensemble that favours the *least* severe point predictions, so the ranking
/// visibly follows the ensemble; counts its ensemble runs and keeps the seeds it was given.
struct EnsembleLfs {
    runs: AtomicUsize,
    seeds: Mutex<Vec<(f64, u64)>>,
}

impl Screener for EnsembleLfs {
    fn screen(&self, test: &TestCase) -> (f64, f64, String) {
        ScriptedLfs.screen(test)
    }
    fn ensemble(&self, test: &TestCase, n: usize, seed: u64) -> Option<Vec<f64>> {
        assert_eq!(n, 8);
        self.runs.fetch_add(1, Ordering::SeqCst);
        let (d, _, _) = ScriptedLfs.screen(test);
        self.seeds.lock().unwrap().push((d, seed));
        // Failing members in an order unrelated to the point prediction's.
        let failing = ((d * 1000.0) as usize) % 9;
        Some((0..8).map(|k| if k < failing { 0.1 } else { 5.0 }).collect())
    }

    fn ensemble_params(&self) -> crate::lfs::ensemble::EnsembleParams {
        crate::lfs::ensemble::EnsembleParams::none()
    }
}

#[test]
fn with_an_ensemble_the_shortlist_flies_by_expected_points_per_minute_and_resumes_from_its_cache() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let lfs = EnsembleLfs {
        runs: AtomicUsize::new(0),
        seeds: Mutex::new(Vec::new()),
    };
    let cfg = CampaignConfig {
        ensemble: 8,
        ..config(4)
    };
    let r = run_campaign(
        &cfg,
        dir.path(),
        &lfs,
        vehicle(&flown, Some(2)),
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(r.suite.flown, 2);
    // At most 2 candidates per flight of the budget get an ensemble.
    let runs = lfs.runs.load(Ordering::SeqCst);
    assert!((1..=8).contains(&runs), "{runs} ensembles");
    // Every flight carries its p_fail; the flights go most expected points (equal flight times: highest
    // p_fail) first, whatever the point prediction says.
    let p: Vec<f64> = r.flights.iter().map(|f| f.predicted_p_fail.unwrap()).collect();
    assert!(p.windows(2).all(|w| w[0] >= w[1]), "{p:?}");
    assert!(p[0] > 0.0);
    assert!(r.suite.lfs_p_fail_brier.is_some());
    assert!(dir.path().join("ensemble.json").is_file());
    // The resume flies the rest without re-running a cached ensemble.
    let r2 = run_campaign(
        &cfg,
        dir.path(),
        &lfs,
        vehicle(&flown, None),
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap();
    assert_eq!(r2.suite.flown, 4);
    assert_eq!(lfs.runs.load(Ordering::SeqCst), runs, "cached ensembles are reused");
    // Seeds depend on the campaign seed and the candidate: distinct candidates, distinct seeds.
    let seeds = lfs.seeds.lock().unwrap().clone();
    let mut distinct: Vec<u64> = seeds.iter().map(|s| s.1).collect();
    distinct.sort_unstable();
    distinct.dedup();
    assert_eq!(distinct.len(), seeds.len());
    assert_ne!(
        crate::campaign::stages::member_seed(3, 0),
        crate::campaign::stages::member_seed(4, 0)
    );
    assert_eq!(
        crate::campaign::stages::member_seed(3, 7),
        crate::campaign::stages::member_seed(3, 7)
    );
}

#[test]
fn a_learning_campaign_calibrates_on_its_flights_adapts_its_draws_and_seeds_the_next_one() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let cfg = CampaignConfig {
        learn: true,
        adapt: true,
        ..config(12)
    };
    let r = run_scripted(&cfg, dir.path(), &flown);
    assert_eq!(r.suite.flown, 12);
    let learnt = r.learning.as_ref().expect("a learning campaign reports what it learnt");
    assert!(learnt.rounds.len() >= crate::campaign::rounds::ROUNDS);
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
            round.local_candidates <= crate::campaign::neighbours::CHILDREN,
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
        .filter(|r| r.min_distance.is_some_and(|d| d < 1.5))
        .map(|r| r.obstacles)
        .collect();
    let d = crate::judge::diversity(&failing);
    assert!(
        failing.len() >= 2 && d.is_some_and(|d| d >= cfg.min_diversity),
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
        let t = TestCase::load(&cfg.case).unwrap().with_obstacles(rec.obstacles);
        assert!(crate::rules::check(&t, &crate::model::Arena::default()).is_empty());
    }
    // The next campaign starts from it: the first round already uses the learnt bias.
    let next_dir = tempfile::tempdir().unwrap();
    let next_cfg = CampaignConfig {
        prior: Some(dir.path().to_path_buf()),
        ..cfg.clone()
    };
    let r2 = run_campaign(
        &next_cfg,
        next_dir.path(),
        &ScriptedLfs,
        vehicle(&flown, None),
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap();
    let l2 = r2.learning.unwrap();
    assert!((l2.rounds[0].bias_m - bias).abs() < 1e-12);
    // The failure counts are this campaign's own.
    assert_eq!(l2.failure_counts.total.flights, 12);
    assert_eq!(
        l2.rounds[0].draw_means,
        std::array::from_fn(|d| learnt.distribution.mean(d))
    );
    // A missing prior is an error naming the file.
    let bad = CampaignConfig {
        prior: Some(next_dir.path().join("nowhere")),
        ..cfg
    };
    let e = run_campaign(
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
    use crate::campaign::diversity_guard::child_max_iou;
    let mut cfg = config(10);
    assert_eq!(
        child_max_iou(&cfg),
        0.5,
        "campaign files before the child rule: max_iou"
    );
    cfg.child_max_iou = Some(0.75);
    assert_eq!(child_max_iou(&cfg), 0.75);
    cfg.child_max_iou = Some(0.3);
    assert_eq!(child_max_iou(&cfg), 0.5);
    let json = serde_json::to_value(config(10)).expect("config serialises");
    let mut old = json.as_object().expect("an object").clone();
    old.remove("child_max_iou");
    let read: CampaignConfig = serde_json::from_value(old.into()).expect("an old campaign.json reads");
    assert_eq!(read.child_max_iou, None);
}

#[test]
fn close_children_stay_within_child_max_iou_of_every_flown_test() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = CampaignConfig {
        learn: true,
        adapt: true,
        min_diversity: 0.0,
        child_max_iou: Some(0.75),
        ..config(24)
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
    let cfg = CampaignConfig {
        learn: true,
        adapt: true,
        ..config(24)
    };
    // Flies 1.5 m farther than the scripted LFS predicts: never below 1.5 m, often within 0.3 m of it.
    let vehicles: Vec<Box<dyn Vehicle>> = vec![Box::new(ScriptedVehicle {
        flown: Arc::new(Mutex::new(Vec::new())),
        stop_after: None,
        count: Arc::new(AtomicUsize::new(0)),
        extra_m: 1.5,
    })];
    let r = run_campaign(
        &cfg,
        dir.path(),
        &ScriptedLfs,
        vehicles,
        &Quiet,
        &AtomicBool::new(false),
    )
    .unwrap();
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
    let cfg = CampaignConfig {
        learn: true,
        adapt: true,
        min_diversity: 0.999,
        ..config(40)
    };
    let r = run_scripted(&cfg, dir.path(), &Arc::new(Mutex::new(Vec::new())));
    let learnt = r.learning.expect("learnt");
    assert!(
        r.suite.failing >= crate::campaign::neighbours::MIN_FAILING_FOR_DIVERSITY,
        "{:?}",
        r.suite
    );
    // Up to session 10 the children paused for the rest of the campaign once the failures were below the floor;
    // now the guard admits those that do not lower the diversity.
    let late: Vec<usize> = learnt.rounds[4..].iter().map(|r| r.local_candidates).collect();
    assert!(late.iter().any(|&c| c > 0), "{:?}", learnt.rounds);
}

/// Flies `left` flights, then is unreachable (a SITL instance whose port or process went away).
struct DyingVehicle {
    left: usize,
}

impl Vehicle for DyingVehicle {
    fn name(&self) -> String {
        "dying".into()
    }
    fn fly(&mut self, test: &TestCase, csv: &Path, _: &AtomicBool) -> Result<Flown, VehicleError> {
        if self.left == 0 {
            return Err(VehicleError::Unreachable {
                vehicle: self.name(),
                reason: "cannot open udpin:0.0.0.0:14540: Address already in use".into(),
            });
        }
        self.left -= 1;
        std::fs::write(csv, "timestamp,x,y,z,r\n0,0,0,0,\n1000000,0,10,10,\n").unwrap();
        let d = (test.obstacles[0].position.y - 20.0).abs() / 2.0;
        Ok(landed(d))
    }
}

#[test]
fn a_campaign_whose_every_vehicle_is_dropped_stops_with_an_error_and_keeps_its_flights() {
    for (learn, adapt) in [(false, false), (true, true)] {
        let dir = tempfile::tempdir().unwrap();
        let cfg = CampaignConfig {
            learn,
            adapt,
            ..config(20)
        };
        let vehicles: Vec<Box<dyn Vehicle>> =
            vec![Box::new(DyingVehicle { left: 3 }), Box::new(DyingVehicle { left: 2 })];
        let e = run_campaign(
            &cfg,
            dir.path(),
            &ScriptedLfs,
            vehicles,
            &Quiet,
            &AtomicBool::new(false),
        )
        .expect_err("no vehicle is left after 5 flights")
        .to_string();
        assert!(
            e.contains("no reachable vehicle") && e.contains("Address already in use"),
            "{e}"
        );
        assert!(e.contains("--resume"), "{e}");
        let journal = Journal::read(&dir.path().join("journal.jsonl")).unwrap();
        assert_eq!(journal.len(), 5, "learn {learn}: the flights before the drop are kept");
    }
}
