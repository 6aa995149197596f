//! One vehicle's worker: takes the next job, flies it, journals it, and gives the job back when its vehicle
//! drops out.

use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Instant;

use crate::campaign::fly::confirm::trajectory_name;
use crate::campaign::fly::retry::fly_counting_rejections;
use crate::campaign::fly::vehicle::{Job, Vehicle, interrupted_if_cancelled};
use crate::campaign::ground::flight_status::FlightStatus;
use crate::campaign::store::journal::{FlightRecord, Journal};

use super::{Fleet, POLL};

impl Fleet<'_> {
    /// One vehicle's worker: flies jobs until the queue is closed and empty, the budget is spent, the campaign
    /// stops, or the vehicle is dropped.
    pub(super) fn work(&self, index: usize, vehicle: &mut dyn Vehicle, mut rejected: usize) {
        while let Some(job) = self.next_job() {
            let rel = trajectory_name(job.candidate, job.tally.next_attempt);
            let t0 = Instant::now();
            let result =
                fly_counting_rejections(vehicle, &job.test, &self.folder.join(&rel), self.cancel, &mut rejected);
            let busy_s = t0.elapsed().as_secs_f64();
            let go_on = match result {
                Ok(flown) => {
                    let flown = interrupted_if_cancelled(flown, self.cancel);
                    let rel = if flown.status == FlightStatus::Interrupted {
                        self.keep_interrupted(rel)
                    } else {
                        rel
                    };
                    let record = job
                        .clone()
                        .record(flown, vehicle.name(), rel, t0.elapsed().as_secs_f64());
                    self.landed(&job, &record, busy_s)
                }
                Err(e) => {
                    self.give_back(index, job, &e.to_string(), busy_s);
                    false
                }
            };
            if !go_on {
                return;
            }
        }
    }

    /// Charges and journals a landed flight (the vehicle busy for `busy_s`), queueing its test's next flight first when it is to be confirmed;
    /// false when the journal could not be written (the worker stops).
    fn landed(&self, job: &Job, record: &FlightRecord, busy_s: f64) -> bool {
        let (round, candidate) = (job.round, job.candidate);
        let mut l = self.lock();
        l.use_.busy_s += busy_s;
        l.last_landing = Some(Instant::now());
        if record.charged() {
            l.finished += 1;
            // Queued before the flight is journaled, so no vehicle takes a new candidate meanwhile.
            if let Some(next) = job.again(&Journal::read_back(record)) {
                *l.outstanding.entry(round).or_default() += 1;
                if l.waves {
                    l.wave_again.push(next);
                } else {
                    l.queue.push_front(next);
                }
            }
        }
        drop(l);
        let journaled = self.journal(round, record);
        let mut l = self.lock();
        l.airborne.retain(|(c, _)| *c != candidate);
        if l.waves && l.airborne.is_empty() {
            l.end_wave();
        }
        l.settle(round);
        drop(l);
        self.changed.notify_all();
        journaled
    }

    /// Gives `job` back to the queue: stopped before it flew, or for another vehicle when vehicle `index` is
    /// out (`why`).
    fn give_back(&self, index: usize, job: Job, why: &str, busy_s: f64) {
        let cancelled = self.cancel.load(Ordering::Relaxed);
        // Why it was dropped is recorded before it stops counting as alive: a campaign woken by the count
        // names the reason in its no-vehicle error.
        if !cancelled {
            self.outcome
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .dropped
                .push(why.to_string());
            self.dead.lock().unwrap_or_else(|p| p.into_inner()).push(index);
        }
        let mut l = self.lock();
        l.use_.busy_s += busy_s;
        l.last_landing = Some(Instant::now());
        l.airborne.retain(|(c, _)| *c != job.candidate);
        l.queue.push_front(job);
        if l.waves && l.airborne.is_empty() {
            l.end_wave();
        }
        if !cancelled {
            l.alive -= 1;
        }
        drop(l);
        self.changed.notify_all();
    }

    /// Moves an interrupted flight's partial trajectory aside (`candidate_N.interrupted.csv`), so flying the
    /// candidate again on resume keeps it; returns where it is.
    pub(super) fn keep_interrupted(&self, rel: PathBuf) -> PathBuf {
        let aside = rel.with_extension("interrupted.csv");
        match std::fs::rename(self.folder.join(&rel), self.folder.join(&aside)) {
            Ok(()) => aside,
            Err(_) => rel, // nothing was recorded: the record keeps the planned path
        }
    }

    /// The next job, or `None` when there will be none (cancelled, stopped, budget spent, or the queue closed
    /// and empty).
    pub(super) fn next_job(&self) -> Option<Job> {
        let mut l = self.lock();
        loop {
            if self.cancel.load(Ordering::Relaxed) || self.stop.load(Ordering::Relaxed) {
                return None;
            }
            l.serve_replays();
            let charged = l.finished + l.airborne.len();
            if charged < l.limit
                && l.replay.allows_new(charged)
                && l.wave_open()
                && let Some(job) = l.queue.pop_front()
            {
                l.wave_taken += 1;
                l.airborne.push((job.candidate, job.test.obstacles.clone()));
                l.first_takeoff.get_or_insert_with(Instant::now);
                return Some(job);
            }
            if l.airborne.is_empty() && !l.open && (l.queue.is_empty() || l.blocked()) {
                return None; // nothing can come: no job will be pushed or handed back
            }
            // A flight in the air may hand its job back, or the campaign push more; wait, bounded so cancel is seen.
            l = self
                .changed
                .wait_timeout(l, POLL)
                .map(|(g, _)| g)
                .unwrap_or_else(|p| p.into_inner().0);
        }
    }

    /// Appends `record` to the journal; on failure stops the fleet and returns false.
    pub(super) fn journal(&self, round: usize, record: &FlightRecord) -> bool {
        let written = self
            .journal
            .lock()
            .map_err(|_| "journal lock poisoned".to_string())
            .and_then(|mut j| {
                j.0.append(record).map_err(|e| e.to_string())?;
                // The journal keeps the record as the file reads it back.
                if record.charged()
                    && let Some(back) = j.0.records().last()
                {
                    let back = back.clone();
                    j.1.push((round, back));
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
