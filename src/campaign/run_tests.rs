//! Campaign pipeline tests with a scripted screener and scripted vehicles (the real LFS and the mock
//! autopilot are exercised by the integration tests).

use crate::campaign::ground::flight_status::FlightStatus;
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use crate::campaign::fly::vehicle::{Flown, Vehicle, VehicleError};
use crate::campaign::ground::screener::Screened;
use crate::campaign::run::{CampaignError, CampaignSettings, Progress, Screener, run_campaign_with};
use crate::campaign::store::journal::Journal;
use crate::generator::adaptive::DIMS;
use crate::model::TestCase;

/// Predicts obstacle 1's centre y minus 20 as the distance: deterministic and spread out.
struct ScriptedLfs;

impl Screener for ScriptedLfs {
    fn screen(&self, test: &TestCase) -> Screened {
        Screened::new((test.obstacles[0].position.y - 20.0).abs() / 2.0, 40.0, "landed")
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
        status: FlightStatus::LANDED,
        min_distance: Some(d),
        min_distance_raw: Some(d),
        flight_time_s: 40.0,
        warnings: Vec::new(),
        reason: None,
        closest_centre_m: None,
        inside_cp_dist: None,
    }
}

struct Quiet;
impl Progress for Quiet {
    fn stage(&self, _: &str, _: usize) {}
    fn tick(&self, _: usize) {}
    fn note(&self, _: &str) {}
}

fn config(budget: usize) -> CampaignSettings {
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
    let mut c = crate::campaign::settings::test_settings(&case, budget);
    // The scripted vehicles stand for MAVLink ones; these tests pass them in.
    c.vehicles.connect = vec!["udpin:127.0.0.1:14540".into()];
    c.campaign.seed = 3;
    c.screening.candidates = 60;
    c.screening.threshold_m = 5.0;
    c.screening.ensemble = 0;
    c.mock.speed = 20.0;
    c.mock.gust_acc_m_s2 = crate::campaign::settings::mock_profile::PX4_SITL_GUST_ACC_M_S2;
    c.learning.learn = false;
    c.learning.adapt = false;
    c.learning.child_max_iou = c.screening.max_iou;
    c.flight.confirm = 1;
    c.flight.overlap = false;
    c
}

/// [`config`] with learning and the adapted generator on.
fn adapted(budget: usize) -> CampaignSettings {
    let mut c = config(budget);
    c.learning.learn = true;
    c.learning.adapt = true;
    c
}

/// `cfg`'s campaign in `dir` with the scripted LFS and vehicles, run to its end.
fn run_scripted(cfg: &CampaignSettings, dir: &Path, flown: &Arc<Mutex<Vec<f64>>>) -> crate::campaign::run::Report {
    run_with(cfg, dir, vehicle(flown, None)).unwrap()
}

/// `cfg`'s campaign in `dir` with the scripted LFS on `vehicles`.
fn run_with(
    cfg: &CampaignSettings,
    dir: &Path,
    vehicles: Vec<Box<dyn Vehicle>>,
) -> Result<crate::campaign::run::Report, CampaignError> {
    run_campaign_with(cfg, dir, &ScriptedLfs, vehicles, &Quiet, &AtomicBool::new(false))
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
    let r = run_campaign_with(
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
    let predicted: Vec<f64> = r.flights.iter().filter_map(|f| f.predicted_min_distance).collect();
    assert!(predicted.windows(2).all(|w| w[0] <= w[1]), "{predicted:?}");
    // Reported tests are exactly the flights below 1.5 m, best first, as valid YAML with their CSVs.
    let failing: Vec<f64> = r
        .flights
        .iter()
        .filter_map(|f| f.min_distance.filter(|d| *d < 1.5))
        .collect();
    // Less the near-duplicate trajectories: the fake vehicle flies tests alike.
    let near_duplicates = r.tests.iter().filter(|t| t.near_duplicate_of.is_some()).count();
    assert_eq!(r.suite.failing + near_duplicates, failing.len());
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
        Some(1.0).filter(|_| r
            .flights
            .iter()
            .any(|f| f.predicted_min_distance.is_some_and(|p| p < 1.5)))
    );
}

#[test]
fn killed_and_resumed_campaign_flies_nothing_twice_and_respects_the_budget() {
    let dir = tempfile::tempdir().unwrap();
    let flown = Arc::new(Mutex::new(Vec::new()));
    let cancel = AtomicBool::new(false);
    let first = run_campaign_with(
        &config(10),
        dir.path(),
        &ScriptedLfs,
        vehicle(&flown, Some(4)),
        &Quiet,
        &cancel,
    );
    assert_eq!(first.unwrap().suite.flown, 4);
    assert_eq!(Journal::read(&dir.path().join("journal.jsonl")).unwrap().len(), 4);
    let second = run_campaign_with(
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
    let third = run_campaign_with(
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
    let mut zero = config(1);
    zero.campaign.budget = 0;
    let e = run_campaign_with(&zero, dir.path(), &ScriptedLfs, vehicle(&flown, None), &Quiet, &quiet).unwrap_err();
    assert!(matches!(e, CampaignError::Config(_)), "{e}");
    let mut bad = config(3);
    bad.campaign.case = "missions/does-not-exist.yaml".into();
    let e = run_campaign_with(&bad, dir.path(), &ScriptedLfs, vehicle(&flown, None), &Quiet, &quiet).unwrap_err();
    assert!(e.to_string().contains("does-not-exist.yaml"), "{e}");
}

/// The scripted screener with an ensemble that favours the *least* severe point predictions, so the ranking
/// visibly follows the ensemble; counts its ensemble runs and keeps the seeds it was given.
struct EnsembleLfs {
    runs: AtomicUsize,
    seeds: Mutex<Vec<(f64, u64)>>,
}

impl Screener for EnsembleLfs {
    fn screen(&self, test: &TestCase) -> Screened {
        ScriptedLfs.screen(test)
    }
    fn ensemble(&self, test: &TestCase, n: usize, seed: u64) -> Option<Vec<f64>> {
        assert_eq!(n, 8);
        self.runs.fetch_add(1, Ordering::SeqCst);
        let d = ScriptedLfs.screen(test).min_distance_m;
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
    let cfg = {
        let mut c = config(4);
        c.screening.ensemble = 8;
        c
    };
    let r = run_campaign_with(
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
    let r2 = run_campaign_with(
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
        crate::campaign::screen::stages::member_seed(3, 0),
        crate::campaign::screen::stages::member_seed(4, 0)
    );
    assert_eq!(
        crate::campaign::screen::stages::member_seed(3, 7),
        crate::campaign::screen::stages::member_seed(3, 7)
    );
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
        let cfg = {
            let mut c = config(20);
            c.learning.learn = learn;
            c.learning.adapt = adapt;
            c
        };
        let vehicles: Vec<Box<dyn Vehicle>> =
            vec![Box::new(DyingVehicle { left: 3 }), Box::new(DyingVehicle { left: 2 })];
        let e = run_with(&cfg, dir.path(), vehicles)
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

#[path = "run_learning_tests.rs"]
mod learning;

#[path = "run_confirm_tests.rs"]
mod confirm;

#[path = "run_overlap_tests.rs"]
mod overlap;

/// A run reads its journal file once, new or resumed, learning or not: every stage asks the journal in memory.
#[test]
fn a_run_reads_the_journal_file_once() {
    use crate::campaign::store::journal::READS;
    for cfg in [config(6), adapted(6)] {
        let dir = tempfile::tempdir().unwrap();
        let flown = Arc::new(Mutex::new(Vec::new()));
        let reads_of = |vehicles, cancel: &AtomicBool| {
            READS.with(|n| n.set(0));
            run_campaign_with(&cfg, dir.path(), &ScriptedLfs, vehicles, &Quiet, cancel).unwrap();
            READS.with(|n| n.get())
        };
        let killed = reads_of(vehicle(&flown, Some(3)), &AtomicBool::new(false));
        let resumed = reads_of(vehicle(&flown, None), &AtomicBool::new(false));
        assert_eq!((killed, resumed), (1, 1), "learn {}", cfg.learning.learn);
        assert_eq!(flown.lock().unwrap().len(), 6, "learn {}", cfg.learning.learn);
    }
}

/// A change to a journal line.
type Edit = dyn Fn(&mut serde_json::Value);

/// `dir`'s journal with its first line changed by `edit`.
fn edit_first_line(dir: &Path, edit: impl Fn(&mut serde_json::Value)) {
    let path = dir.join("journal.jsonl");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut first: serde_json::Value = serde_json::from_str(&lines[0]).unwrap();
    edit(&mut first);
    lines[0] = first.to_string();
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
}

/// A draw no flight shapes (the first round's; every candidate of a campaign that does not learn) must give the
/// journaled obstacles: a line with others comes from another campaign and stops the resume before anything
/// flies, learning or not. So does a candidate index a campaign that does not learn never draws.
#[test]
fn a_journal_line_another_campaign_wrote_stops_the_resume_learning_or_not() {
    let moved = |r: &mut serde_json::Value| {
        let x = r["obstacles"][0]["position"]["x"].as_f64().unwrap();
        r["obstacles"][0]["position"]["x"] = (x + 0.5).into();
    };
    let beyond = |r: &mut serde_json::Value| r["candidate"] = 999.into();
    let cases: [(CampaignSettings, &Edit); 3] = [(config(4), &moved), (adapted(16), &moved), (config(4), &beyond)];
    for (cfg, edit) in cases {
        let dir = tempfile::tempdir().unwrap();
        let flown = Arc::new(Mutex::new(Vec::new()));
        run_with(&cfg, dir.path(), vehicle(&flown, Some(2))).unwrap();
        let before = flown.lock().unwrap().len();
        edit_first_line(dir.path(), edit);
        let e = run_with(&cfg, dir.path(), vehicle(&flown, None))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("another campaign") && e.contains("journal.jsonl") && !e.contains("  "),
            "learn {}: {e}",
            cfg.learning.learn
        );
        assert_eq!(flown.lock().unwrap().len(), before, "nothing flies");
    }
}
