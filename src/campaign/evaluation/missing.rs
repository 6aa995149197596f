//! Why an evaluation is incomplete, said where the user looks (stderr, `report.md`, `report.json`): each
//! backend failure of this run with its reason (repeats counted), each vehicle dropped, each run whose
//! flights all left nothing to judge, or the stop.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use serde::Serialize;

use super::runs::RunState;
use crate::bridge::wire::notices::counted;
use crate::campaign::fly::vehicle::PoolOutcome;
use crate::campaign::ground::flight_status::FlightStatus;
use crate::campaign::store::journal::FlightRecord;
use crate::model::TestCase;

/// The flights an evaluation still lacks, and why.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Missing {
    /// Flights not yet judged (0 when the evaluation is complete).
    pub flights: usize,
    /// Why, one line each (empty when complete).
    pub why: Vec<String>,
}

/// The runs of `runs` still without a flight to judge, and why: `new` are the journal's records of this run,
/// `outcome` what its fleet did, `journal` its file (named in what to do).
pub fn missing(
    runs: &[RunState],
    tests: &[(PathBuf, TestCase)],
    new: &[FlightRecord],
    outcome: &PoolOutcome,
    journal: &Path,
    cancel: &AtomicBool,
) -> Missing {
    let flights = runs.iter().filter(|r| r.judged.is_none()).count();
    if flights == 0 {
        return Missing::default();
    }
    let failed = (new.iter())
        .filter(|r| r.flown.status == FlightStatus::BackendFailed)
        .map(|r| r.flown.reason.as_deref().unwrap_or("no reason given"));
    let mut why: Vec<String> = counted(failed)
        .into_iter()
        .map(|r| format!("a flight failed on its backend: {r}"))
        .collect();
    why.extend(outcome.dropped.iter().map(|d| format!("a vehicle was dropped: {d}")));
    why.extend(runs.iter().filter_map(|r| r.stuck(&tests[r.test].0, journal)));
    if cancel.load(Ordering::SeqCst) {
        why.push("stopped (Ctrl-C, SIGTERM or SIGHUP) before they flew".into());
    }
    if why.is_empty() {
        why.push("not flown in this run (no vehicle took them)".into());
    }
    Missing { flights, why }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::ground::flight_status::Flown;
    use crate::campaign::store::journal::test_record;

    #[test]
    fn every_backend_failure_is_named_once_with_its_count() {
        let run = RunState {
            test: 0,
            run: 0,
            judged: None,
            unjudged: Vec::new(),
        };
        let failed = |reason: &str| FlightRecord {
            flown: Flown::unflown(FlightStatus::BackendFailed, reason.into()),
            ..test_record(0, 1.0, None)
        };
        let new = [
            failed("`false` exited 1"),
            failed("`false` exited 1"),
            test_record(1, 1.0, Some(2.0)),
        ];
        let case = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
        let tests = [(PathBuf::from("test_0.yaml"), TestCase::load(&case).unwrap())];
        let m = missing(
            &[run],
            &tests,
            &new,
            &PoolOutcome::default(),
            Path::new("j"),
            &AtomicBool::new(false),
        );
        assert_eq!(m.flights, 1);
        assert_eq!(m.why, ["a flight failed on its backend: `false` exited 1 (x2)"]);
    }
}
