//! The high-fidelity flight pool: one flight per vehicle at a time, within the budget, each finished flight
//! journaled before the vehicle takes the next one.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex};
use std::time::Instant;

use super::candidate::Screened;
use super::confirm::{Tally, trajectory_name};
use super::journal::{FlightRecord, INTERRUPTED, Journal};
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
    /// The test's flights before this one (none for a new candidate).
    pub tally: Tally,
    /// Flights a failing test gets at most (`--confirm`): a failing flight whose majority is not settled puts
    /// the test's next flight at the front of the queue.
    pub confirm: usize,
}

impl Job {
    /// The first flight of a candidate, not flown again (`--confirm 1`).
    pub fn new(screened: Screened, test: TestCase) -> Self {
        Self {
            screened,
            test,
            tally: Tally::default(),
            confirm: 1,
        }
    }

    /// The test's next flight after `record` (this job's), if its majority is not settled.
    fn again(&self, record: &FlightRecord) -> Option<Job> {
        let tally = self.tally.with(record);
        tally.wants_another(self.confirm).then(|| Job { tally, ..self.clone() })
    }
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
/// `folder` is the campaign folder; trajectories go to `folder/flights/candidate_<n>.csv` (a test's later
/// flights to `candidate_<n>_<flight>.csv`). A failing flight whose test is to be confirmed puts the test's
/// next flight at the front of the queue, before the new candidates: within the budget like any flight.
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
            let rel = trajectory_name(job.screened.candidate, job.tally.next_attempt);
            let t0 = Instant::now();
            let result =
                fly_counting_rejections(vehicle, &job.test, &self.folder.join(&rel), self.cancel, &mut rejected);
            let mut l = self.lock();
            l.in_flight -= 1;
            match result {
                Ok(flown) => {
                    let flown = interrupted_if_cancelled(flown, self.cancel);
                    let rel = if flown.status == INTERRUPTED {
                        self.keep_interrupted(rel)
                    } else {
                        rel
                    };
                    let record = job
                        .clone()
                        .record(flown, vehicle.name(), rel, t0.elapsed().as_secs_f64());
                    if record.charged() {
                        l.finished += 1;
                        // Queued before the flight is journaled, so no vehicle takes a new candidate meanwhile.
                        if let Some(next) = job.again(&Journal::read_back(&record)) {
                            l.queue.push_front(next);
                        }
                    }
                    drop(l);
                    self.changed.notify_all();
                    if !self.journal(&record) {
                        return;
                    }
                }
                Err(_) if self.cancel.load(Ordering::Relaxed) => {
                    // Stopped before it flew: the job stays unflown, the vehicle is not at fault.
                    l.queue.push_front(job);
                    drop(l);
                    self.changed.notify_all();
                    return;
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

    /// Moves an interrupted flight's partial trajectory aside (`candidate_N.interrupted.csv`), so flying the
    /// candidate again on resume keeps it; returns where it is.
    fn keep_interrupted(&self, rel: PathBuf) -> PathBuf {
        let aside = rel.with_extension("interrupted.csv");
        match std::fs::rename(self.folder.join(&rel), self.folder.join(&aside)) {
            Ok(()) => aside,
            Err(_) => rel, // nothing was recorded: the record keeps the planned path
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
            attempt: self.tally.next_attempt,
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
#[path = "pool_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "pool_confirm_tests.rs"]
mod pool_confirm_tests;
