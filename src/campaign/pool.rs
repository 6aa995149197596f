//! The high-fidelity flight pool: one flight per vehicle at a time, within the budget, each finished flight
//! journaled before the vehicle takes the next one.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Instant;

use super::candidate::Screened;
use super::journal::{FlightRecord, INTERRUPTED, Journal, UNCHARGED};
use crate::model::TestCase;

/// How one flight ended, as the vehicle's side reports it.
#[derive(Debug, Clone, PartialEq)]
pub struct Flown {
    /// `landed`, `collision`, `timeout`, `link_lost`, `aborted`, `rejected`, ...
    pub status: String,
    /// The competition's minimum distance, metres, if anything was recorded.
    pub min_distance: Option<f64>,
    /// The un-binned minimum distance, metres.
    pub min_distance_raw: Option<f64>,
    /// Flight time, seconds.
    pub flight_time_s: f64,
    /// What the flight side warned about (e.g. the avoidance planner falling behind).
    pub warnings: Vec<String>,
    /// Why the flight stopped, in words, when it did not land.
    pub reason: Option<String>,
}

/// Why a vehicle could not fly.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VehicleError {
    /// The vehicle cannot be reached or used: the pool drops it and gives its test to another.
    #[error("vehicle {vehicle} unreachable: {reason}")]
    Unreachable {
        /// The vehicle.
        vehicle: String,
        /// Why.
        reason: String,
    },
}

/// A high-fidelity vehicle: the embedded mock, a PX4 SITL instance or a real flight controller.
pub trait Vehicle: Send {
    /// A name for logs and the journal (a MAVLink URL or `mock`).
    fn name(&self) -> String;
    /// Flies `test`, appending the trajectory to `trajectory_csv`; returns when landed or given up.
    fn fly(&mut self, test: &TestCase, trajectory_csv: &Path, cancel: &AtomicBool) -> Result<Flown, VehicleError>;
}

/// One flight to make.
#[derive(Debug, Clone)]
pub struct Job {
    /// The candidate as screened.
    pub screened: Screened,
    /// The test to fly.
    pub test: TestCase,
}

/// What the pool did.
#[derive(Debug, Default)]
pub struct PoolOutcome {
    /// Flights finished (journaled) in this run.
    pub flown: usize,
    /// Those flights' records in journal order, as the journal reads them back.
    pub records: Vec<FlightRecord>,
    /// Vehicles dropped as unreachable, with the reason.
    pub dropped: Vec<String>,
    /// Journal errors (the flight happened but could not be recorded): the campaign stops on the first.
    pub errors: Vec<String>,
}

/// A vehicle that rejects this many flights in a row at setup (status `rejected`: never armed) is dropped, and
/// the last of them is given to another vehicle instead of being journaled. A PX4 SITL instance whose simulated
/// sensors timed out (`MAG #0 failed: TIMEOUT`, "Preflight Fail: No valid data from Compass 0") rejected 8 of a
/// campaign's 30 flights in a row this way, each spending a flight of the budget.
pub const REJECTED_IN_A_ROW_TO_DROP: usize = 2;

/// Shared by the pool's workers: jobs left, flights in the air, flights finished.
struct Ledger {
    queue: VecDeque<Job>,
    in_flight: usize,
    finished: usize,
}

/// What the pool's workers share.
struct Pool<'a> {
    ledger: Mutex<Ledger>,
    changed: Condvar,
    /// The journal and the records appended to it, in its order.
    journal: Mutex<(Journal, Vec<FlightRecord>)>,
    outcome: Mutex<PoolOutcome>,
    stop: AtomicBool,
    /// Indices of the vehicles dropped.
    dead: Mutex<Vec<usize>>,
    budget: usize,
    folder: &'a Path,
    cancel: &'a AtomicBool,
    on_flight: &'a (dyn Fn(&FlightRecord) + Sync),
}

/// Flies `jobs` in order on `vehicles`, at most `budget` flights, appending each to `journal`.
/// `folder` is the campaign folder; trajectories go to `folder/flights/candidate_<n>.csv`.
///
/// A vehicle that turns out unreachable, or rejects [`REJECTED_IN_A_ROW_TO_DROP`] flights in a row, gives its
/// job back; the others wait for that (rather than stopping at a budget that is only reserved) so the job is
/// still flown. Such vehicles are removed from `vehicles`; the others stay for the next call (a learning
/// campaign flies in rounds).
pub fn fly_all(
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    jobs: Vec<Job>,
    budget: usize,
    folder: &Path,
    journal: Journal,
    cancel: &AtomicBool,
    on_flight: &(dyn Fn(&FlightRecord) + Sync),
) -> PoolOutcome {
    // Rejections count across calls (a learning campaign's rounds) and resumes: the journal holds them.
    let history = match Journal::read(journal.path()) {
        Ok(h) => h,
        Err(e) => {
            return PoolOutcome {
                errors: vec![e.to_string()],
                ..PoolOutcome::default()
            };
        }
    };
    let pool = Pool {
        ledger: Mutex::new(Ledger {
            queue: jobs.into_iter().collect(),
            in_flight: 0,
            finished: 0,
        }),
        changed: Condvar::new(),
        journal: Mutex::new((journal, Vec::new())),
        outcome: Mutex::new(PoolOutcome::default()),
        stop: AtomicBool::new(false),
        dead: Mutex::new(Vec::new()),
        budget,
        folder,
        cancel,
        on_flight,
    };
    std::thread::scope(|scope| {
        for (index, vehicle) in vehicles.iter_mut().enumerate() {
            let rejected = rejected_in_a_row(&history, &vehicle.name());
            let pool = &pool;
            scope.spawn(move || pool.work(index, vehicle.as_mut(), rejected));
        }
    });
    let dead = pool.dead.into_inner().unwrap_or_else(|p| p.into_inner());
    let mut index = 0;
    vehicles.retain(|_| {
        index += 1;
        !dead.contains(&(index - 1))
    });
    let mut outcome = pool.outcome.into_inner().unwrap_or_else(|p| p.into_inner());
    outcome.records = pool.journal.into_inner().unwrap_or_else(|p| p.into_inner()).1;
    outcome
}

/// The setup rejections `vehicle` ended its journaled flights with.
fn rejected_in_a_row(history: &[FlightRecord], vehicle: &str) -> usize {
    history
        .iter()
        .rev()
        .filter(|r| r.vehicle == vehicle)
        .take_while(|r| r.status == "rejected")
        .count()
}

impl Pool<'_> {
    fn lock(&self) -> std::sync::MutexGuard<'_, Ledger> {
        self.ledger.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// One vehicle's worker: flies jobs until there are none, the budget is spent, or the vehicle is dropped.
    fn work(&self, index: usize, vehicle: &mut dyn Vehicle, mut rejected: usize) {
        while let Some(job) = self.next_job() {
            let rel = Path::new("flights").join(format!("candidate_{}.csv", job.screened.candidate));
            let t0 = Instant::now();
            let result =
                fly_counting_rejections(vehicle, &job.test, &self.folder.join(&rel), self.cancel, &mut rejected);
            let mut l = self.lock();
            l.in_flight -= 1;
            match result {
                Ok(flown) => {
                    let flown = interrupted_if_cancelled(flown, self.cancel);
                    // An uncharged flight (interrupted, backend failed) leaves its budget to the next job.
                    if !UNCHARGED.contains(&flown.status.as_str()) {
                        l.finished += 1;
                    }
                    drop(l);
                    self.changed.notify_all();
                    let record = job.record(flown, vehicle.name(), rel, t0.elapsed().as_secs_f64());
                    if !self.journal(&record) {
                        return;
                    }
                }
                Err(e) => {
                    // Give the job back for another vehicle; this one is out.
                    l.queue.push_front(job);
                    drop(l);
                    self.changed.notify_all();
                    self.outcome
                        .lock()
                        .unwrap_or_else(|p| p.into_inner())
                        .dropped
                        .push(e.to_string());
                    self.dead.lock().unwrap_or_else(|p| p.into_inner()).push(index);
                    return;
                }
            }
        }
    }

    /// The next job, or `None` when there will be none (cancelled, stopped, budget spent or queue empty).
    fn next_job(&self) -> Option<Job> {
        let mut l = self.lock();
        loop {
            if self.cancel.load(Ordering::Relaxed) || self.stop.load(Ordering::Relaxed) {
                return None;
            }
            let budget_left = l.finished + l.in_flight < self.budget;
            if budget_left && let Some(job) = l.queue.pop_front() {
                l.in_flight += 1;
                return Some(job);
            }
            if l.in_flight == 0 {
                return None; // budget spent or queue empty, and nothing can come back
            }
            // A flight in the air may yet hand its job back; wait, bounded so cancel is seen.
            l = self
                .changed
                .wait_timeout(l, std::time::Duration::from_millis(200))
                .map(|(g, _)| g)
                .unwrap_or_else(|p| p.into_inner().0);
        }
    }

    /// Appends `record` to the journal; on failure stops the pool and returns false.
    fn journal(&self, record: &FlightRecord) -> bool {
        let written = self
            .journal
            .lock()
            .map_err(|_| "journal lock poisoned".to_string())
            .and_then(|mut j| {
                j.0.append(record).map_err(|e| e.to_string())?;
                if record.charged() {
                    j.1.push(Journal::read_back(record));
                }
                Ok(())
            });
        let mut o = self.outcome.lock().unwrap_or_else(|p| p.into_inner());
        match written {
            Ok(()) => {
                o.flown += usize::from(record.charged());
                drop(o);
                (self.on_flight)(record);
                true
            }
            Err(e) => {
                o.errors.push(e);
                self.stop.store(true, Ordering::Relaxed);
                false
            }
        }
    }
}

/// A flight the user's stop cut short (`aborted` after the campaign's cancel) is `interrupted`: not charged,
/// flown again first on resume. A flight that ended on its own while the stop came keeps its status.
fn interrupted_if_cancelled(mut flown: Flown, cancel: &AtomicBool) -> Flown {
    if flown.status == "aborted" && cancel.load(Ordering::Relaxed) {
        flown.status = INTERRUPTED.to_string();
        flown.reason = Some(format!(
            "stopped by the user ({}); not charged to the budget, flown again first on --resume",
            flown.reason.as_deref().unwrap_or("cancelled")
        ));
    }
    flown
}

/// Flies `test` on `vehicle`; the [`REJECTED_IN_A_ROW_TO_DROP`]th setup rejection in a row makes the vehicle
/// unreachable.
fn fly_counting_rejections(
    vehicle: &mut dyn Vehicle,
    test: &TestCase,
    csv: &Path,
    cancel: &AtomicBool,
    rejected_in_a_row: &mut usize,
) -> Result<Flown, VehicleError> {
    match vehicle.fly(test, csv, cancel) {
        Ok(flown) if flown.status == "rejected" => {
            *rejected_in_a_row += 1;
            if *rejected_in_a_row >= REJECTED_IN_A_ROW_TO_DROP {
                Err(VehicleError::Unreachable {
                    vehicle: vehicle.name(),
                    reason: format!(
                        "rejected {rejected_in_a_row} flights in a row at setup (last: {})",
                        flown.reason.as_deref().unwrap_or("no reason given")
                    ),
                })
            } else {
                Ok(flown)
            }
        }
        other => {
            *rejected_in_a_row = 0;
            other
        }
    }
}

impl Job {
    /// The journal record of this job flown by `vehicle`.
    fn record(self, flown: Flown, vehicle: String, trajectory: PathBuf, wall_s: f64) -> FlightRecord {
        FlightRecord {
            candidate: self.screened.candidate,
            obstacles: self.test.obstacles,
            predicted_min_distance: self.screened.min_distance,
            predicted_flight_time_s: self.screened.flight_time_s,
            predicted_p_fail: self.screened.p_fail,
            predicted_raw_min_distance: self.screened.raw_min_distance,
            min_distance: flown.min_distance,
            min_distance_raw: flown.min_distance_raw,
            status: flown.status,
            flight_time_s: flown.flight_time_s,
            warnings: flown.warnings,
            reason: flown.reason,
            vehicle,
            trajectory,
            wall_s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Obstacle, SIM_HOME};
    use std::sync::Arc;

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
                    status: "rejected".into(),
                    min_distance: None,
                    min_distance_raw: None,
                    flight_time_s: 0.0,
                    warnings: Vec::new(),
                    reason: Some("not ready to arm: no valid data from Compass 0".into()),
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
                status: "landed".into(),
                min_distance: Some(1.0),
                min_distance_raw: Some(0.9),
                flight_time_s: 40.0,
                warnings: Vec::new(),
                reason: None,
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

    fn jobs(n: u64) -> Vec<Job> {
        let base = test_case();
        (0..n)
            .map(|i| Job {
                screened: Screened::point(i, 0.5, 40.0, "landed".into()),
                test: base.with_obstacles(vec![Obstacle::new(2.0, 2.0, 20.0, i as f64, 20.0, 0.0)]),
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
        let journal = Journal::open(&dir.path().join("journal.jsonl")).unwrap();
        let out = fly_all(
            &mut v,
            jobs(n),
            budget,
            dir.path(),
            journal,
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
        let journal = || Journal::open(&dir.path().join("journal.jsonl")).unwrap();
        let no_stop = AtomicBool::new(false);
        let first = fly_all(&mut fleet, jobs(2), 2, dir.path(), journal(), &no_stop, &|_| {});
        assert_eq!((first.flown, fleet.len()), (2, 1));
        assert_eq!(fleet[0].name(), "ok");
        let second = fly_all(&mut fleet, jobs(1), 1, dir.path(), journal(), &no_stop, &|_| {});
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
            Journal::open(&path).unwrap(),
            &AtomicBool::new(false),
            &|_| {},
        );
        let records = Journal::read(&path).unwrap();
        assert_eq!(out.dropped.len(), 1, "{:?}", out.dropped);
        assert!(out.dropped[0].contains("rejected 2 flights in a row") && out.dropped[0].contains("Compass"));
        assert_eq!((fleet.len(), fleet[0].name()), (1, "ok".to_string()));
        // One rejection is journaled, the second's job is flown by "ok": the budget is spent on 4 flights.
        let rejected: Vec<_> = records.iter().filter(|r| r.status == "rejected").collect();
        assert_eq!((records.len(), rejected.len(), out.flown), (5, 1, 5));
        let mut ids: Vec<u64> = records.iter().map(|r| r.candidate).collect();
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
            Journal::open(&path).unwrap(),
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
            Journal::open(&path).unwrap(),
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
        let statuses: Vec<&str> = records.iter().map(|r| r.status.as_str()).collect();
        assert_eq!(statuses, vec!["rejected", "landed", "landed"]);
    }

    #[test]
    fn no_reachable_vehicle_flies_nothing() {
        let (out, flown, records) = run(vec![("x", false), ("y", false)], 5, 5);
        assert_eq!((out.flown, flown.len(), records, out.dropped.len()), (0, 0, 0, 2));
    }
}
