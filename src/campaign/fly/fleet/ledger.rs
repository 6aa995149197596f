//! What the fleet's workers and its campaign share under one lock: the queue, the flights in the air, the
//! budget, the waves and the replayed flights.

use crate::campaign::ground::candidate::CandidateId;
use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

use crate::campaign::fly::fleet::replay::Replay;
use crate::campaign::fly::vehicle::{FleetUse, Job};
use crate::campaign::store::journal::FlightRecord;
use crate::model::Obstacle;

/// What the workers and the campaign share, under one lock.
pub(super) struct Ledger {
    pub(super) queue: VecDeque<Job>,
    /// Flights taken and not yet journaled: candidate and obstacles.
    pub(super) airborne: Vec<(CandidateId, Vec<Obstacle>)>,
    /// Charged flights journaled.
    pub(super) finished: usize,
    /// Charged flights the fleet may make in all, raised as rounds are pushed.
    pub(super) limit: usize,
    /// More jobs may be pushed: idle workers wait rather than stop.
    pub(super) open: bool,
    /// Workers still running (a dropped vehicle's worker stops).
    pub(super) alive: usize,
    /// Jobs queued, in the air or being journaled, by round.
    pub(super) outstanding: BTreeMap<usize, usize>,
    pub(super) use_: FleetUse,
    pub(super) first_takeoff: Option<Instant>,
    pub(super) last_landing: Option<Instant>,
    /// Fly in waves (see [`FleetSetup::waves`]).
    pub(super) waves: bool,
    /// Jobs taken in the wave in the air.
    pub(super) wave_taken: usize,
    /// Re-flights the wave in the air asked for, queued when it has landed.
    pub(super) wave_again: Vec<Job>,
    /// A resumed campaign's journaled flights, taken in place of flying them.
    pub(super) replay: Replay,
    /// Flights taken from the replay and not yet collected, with their round.
    pub(super) replayed: Vec<(usize, FlightRecord)>,
}

impl Ledger {
    /// The wave in the air has landed: its re-flights go to the front of the queue, in the order of their tests
    /// (not of their landings), and the next wave may take off.
    pub(super) fn end_wave(&mut self) {
        let mut again = std::mem::take(&mut self.wave_again);
        again.sort_by_key(|j| (j.candidate, j.tally.next_attempt));
        for job in again.into_iter().rev() {
            self.queue.push_front(job);
        }
        self.wave_taken = 0;
    }

    pub(super) fn settle(&mut self, round: usize) {
        if let Some(n) = self.outstanding.get_mut(&round) {
            *n = n.saturating_sub(1);
            if *n == 0 {
                self.outstanding.remove(&round);
            }
        }
    }

    pub(super) fn outstanding_through(&self, round: usize) -> usize {
        self.outstanding.range(..=round).map(|(_, n)| n).sum()
    }

    /// A wave may take another job.
    pub(super) fn wave_open(&self) -> bool {
        !self.waves || self.wave_taken < self.alive
    }

    /// No queued job may take off: the round's budget is spent, or only new flights are queued and the budget
    /// is held by journaled flights not yet replayed.
    pub(super) fn blocked(&self) -> bool {
        let charged = self.finished + self.airborne.len();
        charged >= self.limit || (!self.replay.any_in(&self.queue) && !self.replay.allows_new(charged))
    }

    /// Takes the queued jobs the journal already holds, as if each had flown and landed at once (re-flights
    /// queued, waves ended), within the same budget and waves as flights.
    pub(super) fn serve_replays(&mut self) {
        loop {
            while self.finished + self.airborne.len() < self.limit && self.wave_open() {
                let Some((job, record)) = self.replay.take_next(&mut self.queue) else {
                    break;
                };
                self.wave_taken += 1;
                self.finished += 1;
                if let Some(next) = job.again(&record) {
                    *self.outstanding.entry(job.round).or_default() += 1;
                    if self.waves {
                        self.wave_again.push(next);
                    } else {
                        self.queue.push_front(next);
                    }
                }
                self.replayed.push((job.round, record));
                self.settle(job.round);
            }
            // A wave of replayed flights only has landed once no flight of it is in the air and it can take no
            // more: then its re-flights are queued, and may be replayed in turn.
            let can_take = !self.queue.is_empty() && self.wave_open() && !self.blocked();
            if !(self.waves && self.wave_taken > 0 && self.airborne.is_empty() && !can_take) {
                return;
            }
            self.end_wave();
            if !self.replay.any_in(&self.queue) {
                return;
            }
        }
    }
}
