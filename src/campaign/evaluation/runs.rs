//! The runs of an evaluation, read from its journal: run `k` of test `i` is candidate `i * RUN_STRIDE + k`,
//! judged on its first journaled flight that left something to judge. A flight that left nothing (no
//! trajectory, a deleted or damaged file, a record of a moment) is not counted, and its run is flown again
//! as the run's next flight, up to [`MAX_TRIES`] flights; after that the run stays missing, and
//! [`RunState::stuck`] says what to do. Without the retry one such flight would leave the evaluation incomplete
//! for good.

use std::path::{Path, PathBuf};

use crate::campaign::fly::vehicle::Job;
use crate::campaign::ground::candidate_id::CandidateId;
use crate::campaign::store::journal::FlightRecord;
use crate::campaign::store::trust::read_inside_flight;
use crate::model::competition::flight_time_rule;
use crate::model::{TestCase, Trajectory};

/// Candidate numbers per test: runs are `i * RUN_STRIDE + k`, `k` below this.
pub const RUN_STRIDE: u64 = 100;

/// Flights one run gets at most when they leave nothing to judge.
pub const MAX_TRIES: usize = 3;

/// A flight journaled for a run that left nothing to judge.
#[derive(Debug, Clone)]
pub struct Unjudged {
    /// Its journal line (0 when not known).
    pub line: usize,
    /// Its record.
    pub record: FlightRecord,
    /// Why it cannot be judged.
    pub why: String,
}

/// One run of one test.
#[derive(Debug, Clone)]
pub struct RunState {
    /// The test's index in the suite.
    pub test: usize,
    /// The run's number, from 0.
    pub run: usize,
    /// The flight it is judged on: its file and trajectory.
    pub judged: Option<(PathBuf, Trajectory)>,
    /// The flights before it (or without it) that left nothing to judge, in flight order.
    pub unjudged: Vec<Unjudged>,
}

impl RunState {
    /// Its candidate number in the journal.
    pub fn candidate(&self) -> CandidateId {
        CandidateId(self.test as u64 * RUN_STRIDE + self.run as u64)
    }

    /// Whether it is to be flown (again): not judged, and fewer than [`MAX_TRIES`] flights spent on it.
    pub fn flies_again(&self) -> bool {
        self.judged.is_none() && self.unjudged.len() < MAX_TRIES
    }

    /// Its next flight: the test, numbered after its flights so far.
    pub fn job(&self, test: &TestCase) -> Job {
        let mut job = Job::new(self.candidate(), None, test.clone());
        job.tally.next_attempt = self.unjudged.iter().map(|u| u.record.attempt + 1).max().unwrap_or(0);
        job
    }

    /// What to say of a flight of this run that left nothing to judge (`u`), in `test` (its file).
    pub fn warning(&self, u: &Unjudged, test: &Path) -> String {
        let then = if self.flies_again() {
            format!(
                "flown again (flight {} of at most {MAX_TRIES})",
                self.unjudged.len() + 1
            )
        } else {
            "not flown again".to_string()
        };
        format!(
            "run {} of {} ({}, {}{}) left nothing to judge ({}): not counted; {then}",
            self.run,
            test.display(),
            u.record.trajectory.display(),
            u.record.flown.status,
            u.record
                .flown
                .reason
                .as_deref()
                .map_or(String::new(), |r| format!(": {r}")),
            u.why
        )
    }

    /// Why the run stays missing and what to do, once its [`MAX_TRIES`] flights all left nothing to judge.
    pub fn stuck(&self, test: &Path, journal: &Path) -> Option<String> {
        if self.judged.is_some() || self.flies_again() {
            return None;
        }
        let last = self.unjudged.last()?;
        let lines: Vec<String> = self.unjudged.iter().map(|u| u.line.to_string()).collect();
        Some(format!(
            "run {} of {}: its {} flights all left nothing to judge (the last: {}{}; {}); it is not flown \
             again: fix what failed, then delete lines {} of {} and run the same command again",
            self.run,
            test.display(),
            self.unjudged.len(),
            last.record.flown.status,
            last.record
                .flown
                .reason
                .as_deref()
                .map_or(String::new(), |r| format!(": {r}")),
            last.why,
            lines.join(", "),
            journal.display()
        ))
    }
}

/// Every run of `tests` (`runs` each, test by test) from the charged flights in `records` (each with its
/// journal line), trajectories read from `folder`.
pub fn read_runs(
    tests: &[(PathBuf, TestCase)],
    records: &[(usize, FlightRecord)],
    folder: &Path,
    runs: usize,
) -> Vec<RunState> {
    let mut out = Vec::with_capacity(tests.len() * runs);
    for test in 0..tests.len() {
        for run in 0..runs {
            let mut r = RunState {
                test,
                run,
                judged: None,
                unjudged: Vec::new(),
            };
            let candidate = r.candidate();
            let mut mine: Vec<&(usize, FlightRecord)> = (records.iter())
                .filter(|(_, rec)| rec.charged() && rec.candidate == candidate)
                .collect();
            mine.sort_by_key(|(_, rec)| rec.attempt);
            for (line, record) in mine {
                match judgeable(folder, record) {
                    Ok(flight) => {
                        r.judged = Some(flight);
                        break;
                    }
                    Err(why) => r.unjudged.push(Unjudged {
                        line: *line,
                        record: record.clone(),
                        why,
                    }),
                }
            }
            out.push(r);
        }
    }
    out
}

/// The flight `record` left, read from `folder`, or why there is nothing to judge.
fn judgeable(folder: &Path, record: &FlightRecord) -> Result<(PathBuf, Trajectory), String> {
    if record.trajectory.as_os_str().is_empty() {
        return Err("no trajectory was recorded".into());
    }
    let flight = read_inside_flight(folder, &record.trajectory)?;
    if let Some(why) = flight_time_rule(flight.duration_s()) {
        return Err(format!("{}: {why}", folder.join(&record.trajectory).display()));
    }
    Ok((folder.join(&record.trajectory), flight))
}

#[cfg(test)]
#[path = "runs_tests.rs"]
mod tests;
