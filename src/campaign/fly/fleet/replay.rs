//! A resumed learning campaign replays its plan: it plans every round again from the start, and the fleet takes
//! the flights the journal already holds in place of flying them. Each round then sees the flights the
//! uninterrupted campaign saw when it planned that round, so on repeatable vehicles (the lockstep mock) the
//! resumed campaign ends as the uninterrupted one would have, bit for bit.

use crate::campaign::ground::candidate_id::CandidateId;
use std::collections::{BTreeMap, BTreeSet, VecDeque};

use crate::campaign::fly::vehicle::Job;
use crate::campaign::store::journal::FlightRecord;

/// The journaled flights not yet taken by the replayed plan.
#[derive(Debug)]
pub struct Replay {
    /// By (candidate, attempt): the record's position in the journal, and the record.
    records: BTreeMap<(CandidateId, u32), (usize, FlightRecord)>,
    /// The campaign's budget: a new flight takes off only while it and the journaled flights not yet taken stay
    /// within it, so a journaled flight the replayed plan never asks for still counts.
    budget: usize,
    /// Candidates whose journaled flights are not served: the replayed draw gave them other obstacles.
    aside: BTreeSet<CandidateId>,
}

impl Replay {
    /// Nothing to replay: a new campaign.
    pub fn none() -> Self {
        Self {
            records: BTreeMap::new(),
            budget: usize::MAX,
            aside: BTreeSet::new(),
        }
    }

    /// The charged flights of `journal` (in its order), for a campaign of `budget` flights.
    pub fn new(journal: &[FlightRecord], budget: usize) -> Self {
        let records = (journal.iter().enumerate())
            .filter(|(_, r)| r.charged())
            .map(|(i, r)| ((r.candidate, r.attempt), (i, r.clone())))
            .collect();
        Self {
            records,
            budget,
            aside: BTreeSet::new(),
        }
    }

    /// Stops serving the journaled flights of the candidates in `range` that `as_drawn` says were drawn with
    /// other obstacles this time (they stay pending: counted in the budget, and left over); returns those
    /// candidates, sorted.
    pub fn set_aside_diverged(
        &mut self,
        range: std::ops::Range<u64>,
        as_drawn: impl Fn(&FlightRecord) -> bool,
    ) -> Vec<CandidateId> {
        let mut diverged: Vec<CandidateId> = (self.records.values())
            .filter(|(_, r)| range.contains(&r.candidate.0) && !as_drawn(r))
            .map(|(_, r)| r.candidate)
            .collect();
        diverged.dedup();
        self.aside.extend(&diverged);
        diverged
    }

    /// The candidates whose journaled flights are set aside: never flown again under their identity.
    pub fn aside(&self) -> Vec<CandidateId> {
        self.aside.iter().copied().collect()
    }

    /// The journaled flight a job would be served, if any.
    fn served(&self, job: &Job) -> Option<&(usize, FlightRecord)> {
        let (candidate, attempt) = key(job);
        if self.aside.contains(&candidate) {
            return None;
        }
        self.records.get(&(candidate, attempt))
    }

    /// Journaled flights not yet taken.
    pub fn pending(&self) -> usize {
        self.records.len()
    }

    /// Whether a new flight may take off with `charged` flights journaled or in the air.
    pub fn allows_new(&self, charged: usize) -> bool {
        charged + self.pending() < self.budget
    }

    /// Whether `queue` holds a journaled flight.
    pub fn any_in(&self, queue: &VecDeque<Job>) -> bool {
        !self.records.is_empty() && queue.iter().any(|j| self.served(j).is_some())
    }

    /// Takes the queued job journaled earliest out of `queue`, with its record: the replay hands the flights
    /// back in the order they were journaled, as the uninterrupted campaign learnt from them.
    pub fn take_next(&mut self, queue: &mut VecDeque<Job>) -> Option<(Job, FlightRecord)> {
        let (at, _) = (queue.iter().enumerate())
            .filter_map(|(at, j)| self.served(j).map(|(line, _)| (at, *line)))
            .min_by_key(|(_, line)| *line)?;
        let job = queue.remove(at)?;
        let (_, record) = self.records.remove(&key(&job))?;
        Some((job, record))
    }

    /// The journaled flights the replayed plan never asked for, in journal order.
    pub fn into_left(self) -> Vec<FlightRecord> {
        let mut left: Vec<(usize, FlightRecord)> = self.records.into_values().collect();
        left.sort_by_key(|(line, _)| *line);
        left.into_iter().map(|(_, r)| r).collect()
    }
}

fn key(job: &Job) -> (CandidateId, u32) {
    (job.candidate, job.tally.next_attempt)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::ground::candidate::LfsPrediction;
    use crate::model::TestCase;

    fn record(candidate: u64, attempt: u32, status: &str) -> FlightRecord {
        let line = format!(
            r#"{{"candidate":{candidate},"attempt":{attempt},"obstacles":[],"predicted_min_distance":1.0,
            "predicted_flight_time_s":1.0,"min_distance":1.2,"status":"{status}","flight_time_s":1.0,
            "vehicle":"mock","trajectory":"flights/x.csv","wall_s":1.0}}"#
        );
        serde_json::from_str(&line).unwrap()
    }

    fn job(candidate: u64) -> Job {
        let case = TestCase::load(std::path::Path::new("missions/mission2.yaml")).unwrap();
        let p = LfsPrediction::point(CandidateId(candidate), 1.0, 1.0, "landed".into());
        Job::new(CandidateId(candidate), Some(p), case)
    }

    #[test]
    fn queued_flights_come_back_in_journal_order_and_uncharged_ones_are_flown_again() {
        let journal = [
            record(7, 0, "landed"),
            record(3, 0, "interrupted"),
            record(5, 0, "landed"),
        ];
        let mut replay = Replay::new(&journal, 10);
        assert_eq!(replay.pending(), 2);
        let mut queue: VecDeque<Job> = [3, 5, 7].into_iter().map(job).collect();
        let (first, r) = replay.take_next(&mut queue).unwrap();
        assert_eq!((first.candidate.0, r.candidate.0), (7, 7));
        let (second, _) = replay.take_next(&mut queue).unwrap();
        assert_eq!(second.candidate.0, 5);
        assert!(
            replay.take_next(&mut queue).is_none(),
            "the interrupted flight is flown, not replayed"
        );
        assert_eq!(queue.len(), 1);
        assert!(!replay.any_in(&queue));
    }

    #[test]
    fn flights_never_asked_for_keep_their_place_in_the_budget() {
        let journal = [record(1, 0, "landed"), record(2, 0, "landed"), record(4, 0, "landed")];
        let mut replay = Replay::new(&journal, 5);
        let mut queue: VecDeque<Job> = [2].into_iter().map(job).collect();
        replay.take_next(&mut queue).unwrap();
        // 1 taken, 2 left unasked: with 2 charged, one more new flight fits in 5, not two.
        assert!(replay.allows_new(2));
        assert!(!replay.allows_new(3));
        let left: Vec<u64> = replay.into_left().iter().map(|r| r.candidate.0).collect();
        assert_eq!(left, [1, 4]);
        assert!(Replay::none().allows_new(1_000_000));
    }
}
