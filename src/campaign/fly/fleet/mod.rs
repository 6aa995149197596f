//! The fleet: one worker per vehicle taking jobs from one queue, each finished flight journaled before the
//! vehicle takes the next. The queue can stay open while the campaign plans its next round, so the vehicles
//! fly while the LFS screens: a round's jobs are pushed with the budget they may use, and the campaign waits
//! for a round's flights only when it needs them to learn. A resumed campaign's journaled flights are taken
//! from its [`Replay`] as their jobs come up, in place of flying them.

use crate::campaign::ground::candidate::CandidateId;
use std::collections::{BTreeMap, VecDeque};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard};
use std::time::Duration;

use crate::campaign::fly::fleet::replay::Replay;
use crate::campaign::fly::retry::rejected_in_a_row;
use crate::campaign::fly::vehicle::{FleetUse, Job, PoolOutcome, Vehicle};
use crate::campaign::store::journal::{FlightRecord, Journal};
use crate::model::Obstacle;

/// How long an idle worker or a waiting campaign sleeps before looking at the cancel flag again.
const POLL: Duration = Duration::from_millis(200);

mod ledger;
pub mod replay;
mod worker;

use ledger::Ledger;

/// The fleet as the campaign sees it while the workers fly.
pub struct Fleet<'a> {
    ledger: Mutex<Ledger>,
    changed: Condvar,
    /// The journal, and the charged flights appended to it and not yet collected, with their round, in its order.
    journal: Mutex<(&'a mut Journal, Vec<(usize, FlightRecord)>)>,
    outcome: Mutex<PoolOutcome>,
    stop: AtomicBool,
    /// Indices of the vehicles dropped.
    dead: Mutex<Vec<usize>>,
    folder: &'a Path,
    cancel: &'a AtomicBool,
    on_flight: &'a (dyn Fn(&FlightRecord) + Sync),
}

/// Where the fleet writes, and what stops it.
pub struct FleetSetup<'a> {
    /// The campaign folder: trajectories go under `flights/`.
    pub folder: &'a Path,
    /// The campaign's journal, each flight appended as it lands (and kept in its memory).
    pub journal: &'a mut Journal,
    /// The campaign's stop: vehicles in the air land, none takes off.
    pub cancel: &'a AtomicBool,
    /// Told of each journaled flight.
    pub on_flight: &'a (dyn Fn(&FlightRecord) + Sync),
    /// Fly in waves: one job per vehicle, the next wave only once the whole wave has landed, and each round's
    /// flights handed back sorted by test. Which flights a campaign makes, and in which order it learns from
    /// them, then no longer depends on which vehicle lands first: with repeatable vehicles (the lockstep mock)
    /// the same seed flies the same campaign, re-flights included. Costs the vehicles' idle time at the end of
    /// each wave.
    pub waves: bool,
    /// A resumed campaign's journaled flights, taken in place of flying them when its plan queues them.
    pub replay: Replay,
}

/// Runs `body` on this thread while a worker per vehicle flies what it pushes; when `body` returns, the queue
/// closes (the workers fly what is left in it, within the budget, then stop). Vehicles dropped as unreachable
/// are removed from `vehicles`. Returns `body`'s result and what the fleet did.
pub fn run_fleet<R>(
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    setup: FleetSetup<'_>,
    body: impl FnOnce(&Fleet) -> R,
) -> (R, PoolOutcome) {
    // Rejections count across calls (a campaign's stages) and resumes: the journal holds them.
    let history = setup.journal.charged();
    let fleet = Fleet::new(setup, vehicles.len());
    let result = std::thread::scope(|scope| {
        for (index, vehicle) in vehicles.iter_mut().enumerate() {
            let rejected = rejected_in_a_row(&history, &vehicle.name());
            let fleet = &fleet;
            scope.spawn(move || fleet.work(index, vehicle.as_mut(), rejected));
        }
        let result = body(&fleet);
        fleet.lock().open = false;
        fleet.changed.notify_all();
        result
    });
    let dead = fleet.dead.into_inner().unwrap_or_else(|p| p.into_inner());
    let mut index = 0;
    vehicles.retain(|_| {
        index += 1;
        !dead.contains(&(index - 1))
    });
    let ledger = fleet.ledger.into_inner().unwrap_or_else(|p| p.into_inner());
    let mut outcome = fleet.outcome.into_inner().unwrap_or_else(|p| p.into_inner());
    let journaled = fleet.journal.into_inner().unwrap_or_else(|p| p.into_inner()).1;
    outcome.records = journaled.into_iter().map(|(_, r)| r).collect();
    outcome.fleet = FleetUse {
        span_s: match (ledger.first_takeoff, ledger.last_landing) {
            (Some(a), Some(b)) => b.saturating_duration_since(a).as_secs_f64(),
            _ => 0.0,
        },
        ..ledger.use_
    };
    (result, outcome)
}

/// Flies `jobs` in order on `vehicles`, at most `budget` flights, appending each to `journal`.
/// `folder` is the campaign folder; trajectories go to `folder/flights/candidate_<n>.csv` (a test's later
/// flights to `candidate_<n>_<flight>.csv`). A failing flight whose test is to be confirmed puts the test's
/// next flight at the front of the queue, before the new candidates: within the budget like any flight.
///
/// A vehicle that turns out unreachable, or rejects [`super::retry::REJECTED_IN_A_ROW_TO_DROP`] flights in a row, gives its
/// job back; the others wait for that (rather than stopping at a budget that is only reserved) so the job is
/// still flown. Such vehicles are removed from `vehicles`; the others stay for the next call.
pub fn fly_all(
    vehicles: &mut Vec<Box<dyn Vehicle>>,
    jobs: Vec<Job>,
    budget: usize,
    folder: &Path,
    journal: &mut Journal,
    cancel: &AtomicBool,
    on_flight: &(dyn Fn(&FlightRecord) + Sync),
) -> PoolOutcome {
    let setup = FleetSetup {
        folder,
        journal,
        cancel,
        on_flight,
        waves: false,
        replay: Replay::none(),
    };
    run_fleet(vehicles, setup, |fleet| fleet.push(0, jobs, budget)).1
}

impl<'a> Fleet<'a> {
    fn new(setup: FleetSetup<'a>, vehicles: usize) -> Self {
        Self {
            ledger: Mutex::new(Ledger {
                queue: VecDeque::new(),
                airborne: Vec::new(),
                finished: 0,
                limit: 0,
                open: true,
                alive: vehicles,
                outstanding: BTreeMap::new(),
                use_: FleetUse {
                    vehicles,
                    ..FleetUse::default()
                },
                first_takeoff: None,
                last_landing: None,
                waves: setup.waves,
                wave_taken: 0,
                wave_again: Vec::new(),
                replay: setup.replay,
                replayed: Vec::new(),
            }),
            changed: Condvar::new(),
            journal: Mutex::new((setup.journal, Vec::new())),
            outcome: Mutex::new(PoolOutcome::default()),
            stop: AtomicBool::new(false),
            dead: Mutex::new(Vec::new()),
            folder: setup.folder,
            cancel: setup.cancel,
            on_flight: setup.on_flight,
        }
    }

    fn lock(&self) -> MutexGuard<'_, Ledger> {
        self.ledger.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Queues `jobs` as round `round`'s (after those queued before) and lets the fleet make `limit` charged
    /// flights in all (a limit below the current one is ignored).
    pub fn push(&self, round: usize, jobs: Vec<Job>, limit: usize) {
        let mut l = self.lock();
        l.limit = l.limit.max(limit);
        for mut job in jobs {
            job.round = round;
            *l.outstanding.entry(round).or_default() += 1;
            l.queue.push_back(job);
        }
        drop(l);
        self.changed.notify_all();
    }

    /// Waits until every job of round `round` and earlier is journaled, or can no longer be flown (budget
    /// spent, no vehicle left, cancelled, journal failed); drops those still queued (they stay unflown) and
    /// returns their charged flights, in journal order, not returned before.
    pub fn wait_round(&self, round: usize) -> Vec<FlightRecord> {
        let mut l = self.lock();
        while l.outstanding_through(round) > 0 && !self.stuck(&l) {
            l = self
                .changed
                .wait_timeout(l, POLL)
                .map(|(g, _)| g)
                .unwrap_or_else(|p| p.into_inner().0);
        }
        let queued = std::mem::take(&mut l.queue);
        for job in queued {
            if job.round <= round {
                l.settle(job.round);
            } else {
                l.queue.push_back(job);
            }
        }
        let waves = l.waves;
        // Replayed flights were journaled before any flight of this run.
        let (replayed, later): (Vec<_>, Vec<_>) = std::mem::take(&mut l.replayed)
            .into_iter()
            .partition(|(r, _)| *r <= round);
        l.replayed = later;
        drop(l);
        let mut j = self.journal.lock().unwrap_or_else(|p| p.into_inner());
        let (mine, later): (Vec<_>, Vec<_>) = std::mem::take(&mut j.1).into_iter().partition(|(r, _)| *r <= round);
        j.1 = later;
        let mut records: Vec<FlightRecord> = replayed.into_iter().chain(mine).map(|(_, r)| r).collect();
        if waves {
            records.sort_by_key(|r| (r.candidate, r.attempt));
        }
        records
    }

    /// No queued job can be taken any more, and nothing in the air can change that.
    fn stuck(&self, l: &Ledger) -> bool {
        let halted = self.cancel.load(Ordering::Relaxed) || self.stop.load(Ordering::Relaxed) || l.alive == 0;
        l.airborne.is_empty() && (halted || l.blocked())
    }

    /// Charged flights journaled, plus jobs queued or in the air: what the budget has promised.
    pub fn committed(&self) -> usize {
        let l = self.lock();
        l.finished + l.airborne.len() + l.queue.len()
    }

    /// The candidates queued, in the air, or flown and not yet collected by [`Self::wait_round`].
    pub fn busy(&self) -> Vec<(CandidateId, Vec<Obstacle>)> {
        let l = self.lock();
        let mut busy: Vec<(CandidateId, Vec<Obstacle>)> = (l.queue.iter())
            .map(|j| (j.candidate, j.test.obstacles.clone()))
            .chain(l.airborne.iter().cloned())
            .chain(l.replayed.iter().map(|(_, r)| (r.candidate, r.obstacles.clone())))
            .collect();
        drop(l);
        let j = self.journal.lock().unwrap_or_else(|p| p.into_inner());
        busy.extend(j.1.iter().map(|(_, r)| (r.candidate, r.obstacles.clone())));
        busy
    }

    /// Vehicles still flying (a dropped one is gone).
    pub fn alive(&self) -> usize {
        self.lock().alive
    }

    /// The vehicles dropped so far, with why.
    pub fn dropped(&self) -> Vec<String> {
        self.outcome.lock().unwrap_or_else(|p| p.into_inner()).dropped.clone()
    }

    /// The first journal error (the fleet stopped on it).
    pub fn journal_error(&self) -> Option<String> {
        self.outcome
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .errors
            .first()
            .cloned()
    }

    /// Stops serving the journaled flights of `range`'s candidates drawn otherwise (see
    /// [`Replay::set_aside_diverged`]); returns those candidates.
    pub fn set_aside_diverged(
        &self,
        range: std::ops::Range<u64>,
        as_drawn: impl Fn(&FlightRecord) -> bool,
    ) -> Vec<CandidateId> {
        self.lock().replay.set_aside_diverged(range, as_drawn)
    }

    /// The candidates set aside so far (see [`Replay::aside`]).
    pub fn set_aside(&self) -> Vec<CandidateId> {
        self.lock().replay.aside()
    }

    /// The journaled flights the replayed plan has not asked for; they are no longer served.
    pub fn unreplayed(&self) -> Vec<FlightRecord> {
        std::mem::replace(&mut self.lock().replay, Replay::none()).into_left()
    }

    /// Empties the queue: the flights in the air finish, nothing else takes off.
    pub fn abandon(&self) {
        let mut l = self.lock();
        let queued = std::mem::take(&mut l.queue);
        for job in queued {
            l.settle(job.round);
        }
        drop(l);
        self.changed.notify_all();
    }
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod confirm_tests;
