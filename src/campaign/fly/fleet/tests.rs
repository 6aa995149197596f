//! The fleet: budgets, dropped vehicles, rejections and re-flights, on scripted vehicles.

use super::*;
use crate::campaign::fly::vehicle::*;
use crate::campaign::ground::candidate::{CandidateId, LfsPrediction};
use crate::campaign::ground::flight_status::FlightStatus;
use crate::campaign::store::journal::Journal;
use crate::model::TestCase;
use crate::model::{Obstacle, SIM_HOME};
use std::sync::{Arc, Mutex};

struct Fake {
    name: &'static str,
    reachable: bool,
    log: Arc<Mutex<Vec<(String, u64)>>>,
    /// Set once an unreachable vehicle was tried; reachable ones wait for it (bounded), so a test does not
    /// depend on which thread starts first.
    dead_tried: Option<Arc<AtomicBool>>,
    /// Reachable, but rejects every flight at setup (sets `dead_tried` from its second).
    rejects: bool,
    rejected: usize,
}

impl Vehicle for Fake {
    fn name(&self) -> String {
        self.name.into()
    }
    fn fly(&mut self, test: &TestCase, _csv: &Path, _c: &AtomicBool) -> Result<Flown, VehicleError> {
        if self.rejects {
            self.rejected += 1;
            if let Some(d) = self.dead_tried.as_ref().filter(|_| self.rejected >= 2) {
                d.store(true, Ordering::SeqCst);
            }
            return Ok(Flown {
                status: FlightStatus::REJECTED,
                min_distance: None,
                min_distance_raw: None,
                flight_time_s: 0.0,
                warnings: Vec::new(),
                reason: Some("not ready to arm: no valid data from Compass 0".into()),
                closest_centre_m: None,
                inside_cp_dist: None,
            });
        }
        if !self.reachable {
            if let Some(d) = &self.dead_tried {
                d.store(true, Ordering::SeqCst);
            }
            // Fail slowly, so the other vehicles see the whole budget reserved meanwhile.
            std::thread::sleep(std::time::Duration::from_millis(100));
            return Err(VehicleError::Unreachable {
                vehicle: self.name.into(),
                reason: "no heartbeat".into(),
            });
        }
        if let Some(d) = &self.dead_tried {
            for _ in 0..2000 {
                if d.load(Ordering::SeqCst) {
                    break;
                }
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
        }
        let id = test.obstacles[0].position.x as u64;
        self.log.lock().unwrap().push((self.name.into(), id));
        Ok(Flown {
            status: FlightStatus::LANDED,
            min_distance: Some(1.0),
            min_distance_raw: Some(0.9),
            flight_time_s: 40.0,
            warnings: Vec::new(),
            reason: None,
            closest_centre_m: None,
            inside_cp_dist: None,
        })
    }
}

fn test_case() -> TestCase {
    let yaml = "drone:\n  mission_file: missions/mission2.plan\n";
    TestCase::parse(
        yaml,
        &std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("t.yaml"),
    )
    .unwrap()
}

type Log = Arc<Mutex<Vec<(String, u64)>>>;

fn fake(name: &'static str, reachable: bool, log: &Log, dead_tried: &Option<Arc<AtomicBool>>) -> Box<dyn Vehicle> {
    Box::new(Fake {
        name,
        reachable,
        log: log.clone(),
        dead_tried: dead_tried.clone(),
        rejects: false,
        rejected: 0,
    })
}

/// A vehicle that rejects every flight at setup, setting `dropped` from its second.
fn rejecting(name: &'static str, log: &Log, dropped: &Option<Arc<AtomicBool>>) -> Box<dyn Vehicle> {
    Box::new(Fake {
        name,
        reachable: true,
        log: log.clone(),
        dead_tried: dropped.clone(),
        rejects: true,
        rejected: 0,
    })
}

pub(in crate::campaign) fn jobs(n: u64) -> Vec<Job> {
    let base = test_case();
    (0..n)
        .map(|i| {
            Job::new(
                CandidateId(i),
                Some(LfsPrediction::point(CandidateId(i), 0.5, 40.0, "landed".into())),
                base.with_obstacles(vec![Obstacle::new(2.0, 2.0, 20.0, i as f64, 20.0, 0.0)]),
            )
        })
        .collect()
}

fn run(vehicles: Vec<(&'static str, bool)>, n: u64, budget: usize) -> (PoolOutcome, Vec<(String, u64)>, usize) {
    run_with(vehicles, n, budget, false)
}

/// `wait_for_dead`: reachable vehicles fly only once an unreachable one was tried.
fn run_with(
    vehicles: Vec<(&'static str, bool)>,
    n: u64,
    budget: usize,
    wait_for_dead: bool,
) -> (PoolOutcome, Vec<(String, u64)>, usize) {
    let dir = tempfile::tempdir().unwrap();
    let log = Arc::new(Mutex::new(Vec::new()));
    let dead_tried = wait_for_dead.then(|| Arc::new(AtomicBool::new(false)));
    let mut v: Vec<Box<dyn Vehicle>> = vehicles
        .into_iter()
        .map(|(name, reachable)| fake(name, reachable, &log, &dead_tried))
        .collect();
    let mut journal = Journal::load(&dir.path().join("journal.jsonl")).unwrap().0;
    let out = fly_all(
        &mut v,
        jobs(n),
        budget,
        dir.path(),
        &mut journal,
        &AtomicBool::new(false),
        &|_| {},
    );
    let records = Journal::read(&dir.path().join("journal.jsonl")).unwrap().len();
    let flown = log.lock().unwrap().clone();
    (out, flown, records)
}

#[test]
fn budget_is_respected_across_vehicles() {
    let (out, flown, records) = run(vec![("a", true), ("b", true), ("c", true)], 20, 7);
    assert_eq!((out.flown, flown.len(), records), (7, 7, 7));
    let mut ids: Vec<u64> = flown.iter().map(|f| f.1).collect();
    ids.sort();
    assert_eq!(ids, (0..7).collect::<Vec<_>>(), "the best-ranked jobs, each once");
    let _ = SIM_HOME;
}

#[test]
fn an_unreachable_vehicle_is_dropped_and_its_job_flown_elsewhere() {
    let (out, flown, _) = run_with(vec![("dead", false), ("ok", true)], 5, 5, true);
    assert_eq!(out.flown, 5);
    assert_eq!(out.dropped.len(), 1);
    assert!(flown.iter().all(|f| f.0 == "ok"));
    let mut ids: Vec<u64> = flown.iter().map(|f| f.1).collect();
    ids.sort();
    assert_eq!(ids, vec![0, 1, 2, 3, 4]);
}

#[test]
fn unreachable_vehicles_leave_the_fleet_and_the_others_fly_the_next_round() {
    let dir = tempfile::tempdir().unwrap();
    let log = Arc::new(Mutex::new(Vec::new()));
    // The live vehicle waits until the dead one was tried, so the dead one surely gets a job.
    let dead_tried = Some(Arc::new(AtomicBool::new(false)));
    let mut fleet = vec![
        fake("dead", false, &log, &dead_tried),
        fake("ok", true, &log, &dead_tried),
    ];
    let journal = || Journal::load(&dir.path().join("journal.jsonl")).unwrap().0;
    let no_stop = AtomicBool::new(false);
    let first = fly_all(&mut fleet, jobs(2), 2, dir.path(), &mut journal(), &no_stop, &|_| {});
    assert_eq!((first.flown, fleet.len()), (2, 1));
    assert_eq!(fleet[0].name(), "ok");
    let second = fly_all(&mut fleet, jobs(1), 1, dir.path(), &mut journal(), &no_stop, &|_| {});
    assert_eq!((second.flown, second.dropped.len()), (1, 0));
}

#[test]
fn a_job_handed_back_after_the_budget_was_reserved_is_still_flown() {
    // Budget 1: the dead vehicle reserves it, fails, and the live one must still fly the job.
    for _ in 0..5 {
        let (out, flown, records) = run(vec![("dead", false), ("ok", true)], 3, 1);
        assert_eq!((out.flown, flown.len(), records), (1, 1, 1), "{:?}", out.dropped);
    }
}

#[test]
fn a_vehicle_that_rejects_flights_in_a_row_is_dropped_and_the_last_one_flown_elsewhere() {
    let dir = tempfile::tempdir().unwrap();
    let log = Arc::new(Mutex::new(Vec::new()));
    let dropped = Some(Arc::new(AtomicBool::new(false)));
    // "ok" holds its first job until "bad" has rejected twice.
    let mut fleet = vec![rejecting("bad", &log, &dropped), fake("ok", true, &log, &dropped)];
    let path = dir.path().join("journal.jsonl");
    let out = fly_all(
        &mut fleet,
        jobs(5),
        5,
        dir.path(),
        &mut Journal::load(&path).unwrap().0,
        &AtomicBool::new(false),
        &|_| {},
    );
    let records = Journal::read(&path).unwrap();
    assert_eq!(out.dropped.len(), 1, "{:?}", out.dropped);
    assert!(out.dropped[0].contains("rejected 2 flights in a row") && out.dropped[0].contains("Compass"));
    assert_eq!((fleet.len(), fleet[0].name()), (1, "ok".to_string()));
    // One rejection is journaled, the second's job is flown by "ok": the budget is spent on 4 flights.
    let rejected: Vec<_> = records
        .iter()
        .filter(|r| r.flown.status == FlightStatus::REJECTED)
        .collect();
    assert_eq!((records.len(), rejected.len(), out.flown), (5, 1, 5));
    let mut ids: Vec<u64> = records.iter().map(|r| r.candidate.0).collect();
    ids.sort();
    assert_eq!(ids, vec![0, 1, 2, 3, 4], "every job once");
    assert_eq!(log.lock().unwrap().len(), 4);
}

#[test]
fn rejections_in_a_row_count_across_rounds() {
    let dir = tempfile::tempdir().unwrap();
    let log = Arc::new(Mutex::new(Vec::new()));
    let dropped = Some(Arc::new(AtomicBool::new(false)));
    let mut fleet = vec![rejecting("bad", &log, &dropped)];
    let path = dir.path().join("journal.jsonl");
    let no_stop = AtomicBool::new(false);
    // Round 1: one rejection, journaled; the vehicle stays.
    let first = fly_all(
        &mut fleet,
        jobs(1),
        1,
        dir.path(),
        &mut Journal::load(&path).unwrap().0,
        &no_stop,
        &|_| {},
    );
    assert_eq!((first.flown, first.dropped.len(), fleet.len()), (1, 0, 1));
    // Round 2: its next rejection is the second in a row.
    fleet.push(fake("ok", true, &log, &dropped));
    let mut next = jobs(3);
    next.remove(0);
    let second = fly_all(
        &mut fleet,
        next,
        2,
        dir.path(),
        &mut Journal::load(&path).unwrap().0,
        &no_stop,
        &|_| {},
    );
    assert_eq!(
        (second.flown, second.dropped.len(), fleet.len()),
        (2, 1, 1),
        "{:?}",
        second.dropped
    );
    let records = Journal::read(&path).unwrap();
    let statuses: Vec<&str> = records.iter().map(|r| r.flown.status.as_str()).collect();
    assert_eq!(statuses, vec!["rejected", "landed", "landed"]);
}

#[test]
fn no_reachable_vehicle_flies_nothing() {
    let (out, flown, records) = run(vec![("x", false), ("y", false)], 5, 5);
    assert_eq!((out.flown, flown.len(), records, out.dropped.len()), (0, 0, 0, 2));
}

/// Runs `body` on an open fleet of `vehicles` (name, reachable); returns its result and the outcome.
fn on_fleet<R>(vehicles: Vec<(&'static str, bool)>, body: impl FnOnce(&Fleet) -> R) -> (R, PoolOutcome) {
    let dir = tempfile::tempdir().unwrap();
    let log = Arc::new(Mutex::new(Vec::new()));
    let mut v: Vec<Box<dyn Vehicle>> = vehicles
        .into_iter()
        .map(|(name, reachable)| fake(name, reachable, &log, &None))
        .collect();
    let setup = FleetSetup {
        folder: dir.path(),
        journal: &mut Journal::load(&dir.path().join("journal.jsonl")).unwrap().0,
        cancel: &AtomicBool::new(false),
        on_flight: &|_| {},
        waves: false,
        replay: crate::campaign::fly::fleet::replay::Replay::none(),
    };
    run_fleet(&mut v, setup, body)
}

fn candidates(records: &[FlightRecord]) -> Vec<u64> {
    let mut c: Vec<u64> = records.iter().map(|r| r.candidate.0).collect();
    c.sort_unstable();
    c
}

#[test]
fn an_open_fleet_flies_rounds_as_they_are_pushed_and_returns_each_round_s_flights() {
    let ((first, second), out) = on_fleet(vec![("a", true), ("b", true)], |fleet| {
        // Idle workers wait for work rather than stop.
        std::thread::sleep(std::time::Duration::from_millis(450));
        let mut all = jobs(6);
        let later = all.split_off(3);
        fleet.push(0, all, 3);
        fleet.push(1, later, 6);
        (fleet.wait_round(0), fleet.wait_round(1))
    });
    assert_eq!(candidates(&first), vec![0, 1, 2]);
    assert_eq!(candidates(&second), vec![3, 4, 5]);
    assert_eq!(out.flown, 6);
    assert_eq!(out.fleet.vehicles, 2);
}

#[test]
fn a_round_s_jobs_beyond_its_budget_are_dropped_when_the_campaign_collects_it() {
    let ((flown, committed), out) = on_fleet(vec![("a", true)], |fleet| {
        fleet.push(0, jobs(5), 3);
        let flown = fleet.wait_round(0);
        (flown, fleet.committed())
    });
    assert_eq!(flown.len(), 3);
    assert_eq!(committed, 3, "the two jobs over the budget left the queue");
    assert_eq!(out.flown, 3);
}

#[test]
fn waiting_on_a_fleet_whose_vehicles_are_all_dropped_returns() {
    let ((flown, alive), out) = on_fleet(vec![("dead", false)], |fleet| {
        fleet.push(0, jobs(2), 2);
        (fleet.wait_round(0), fleet.alive())
    });
    assert!(flown.is_empty());
    assert_eq!(alive, 0);
    assert_eq!(out.dropped.len(), 1, "{:?}", out.dropped);
}
