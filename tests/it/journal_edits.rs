//! Any edit of a journal, by hand, by a crash or by someone hostile, either leaves a journal that resumes to a
//! consistent folder (every record believable, each flight once, the file ending on a whole line) or is
//! refused with an error naming the journal.

use prgenuav::campaign::ground::candidate::{CandidateId, LfsPrediction};
use std::path::{Path, PathBuf};

use prgenuav::campaign::fly::vehicle::Flown;
use prgenuav::campaign::ground::flight_status::FlightStatus;
use prgenuav::campaign::store::journal::{FlightRecord, Journal};
use prgenuav::campaign::store::trust::{check_journal, check_record, is_inside};
use proptest::prelude::*;
use serde_json::Value;

/// The arena size the checks use here, metres.
const SIZE_M: f64 = 120.0;

fn record(candidate: u64, status: FlightStatus) -> FlightRecord {
    FlightRecord {
        candidate: CandidateId(candidate),
        attempt: 0,
        obstacles: Vec::new(),
        prediction: Some(LfsPrediction {
            p_fail: Some(0.5),
            ..LfsPrediction::point(CandidateId(candidate), 1.0, 60.0, String::new())
        }),
        flown: Flown {
            min_distance: Some(0.8 + candidate as f64),
            min_distance_raw: Some(0.7 + candidate as f64),
            flight_time_s: 61.0,
            ..Flown::ended(status)
        },
        vehicle: "mock".into(),
        trajectory: PathBuf::from(format!("flights/candidate_{candidate}.csv")),
        wall_s: 2.0,
    }
}

fn journal_text() -> String {
    [
        record(0, FlightStatus::LANDED),
        record(3, FlightStatus::COLLISION),
        record(5, FlightStatus::Interrupted),
        record(7, FlightStatus::LANDED),
    ]
    .iter()
    .map(|r| serde_json::to_string(r).unwrap() + "\n")
    .collect()
}

#[derive(Debug, Clone)]
enum Edit {
    Byte(usize, u8),
    Truncate(usize),
    DeleteLine(usize),
    DuplicateLine(usize),
    Field(usize, &'static str, Value),
}

fn values() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(Value::Null),
        Just(Value::from(-1.0)),
        Just(Value::from(1e300)),
        Just(Value::from(0.0)),
        Just(Value::from(2.5)),
        Just(Value::from("../../etc/passwd")),
        Just(Value::from("/etc/passwd")),
        Just(Value::from("flights/candidate_9.csv")),
        Just(Value::from("landed")),
        Just(Value::from(3u64)),
        any::<i32>().prop_map(Value::from),
    ]
}

fn edits() -> impl Strategy<Value = Edit> {
    let fields = prop::sample::select(vec![
        "candidate",
        "attempt",
        "min_distance",
        "min_distance_raw",
        "flight_time_s",
        "wall_s",
        "trajectory",
        "status",
        "predicted_p_fail",
    ]);
    prop_oneof![
        (0usize..2000, any::<u8>()).prop_map(|(i, b)| Edit::Byte(i, b)),
        (0usize..2000).prop_map(Edit::Truncate),
        (0usize..4).prop_map(Edit::DeleteLine),
        (0usize..4).prop_map(Edit::DuplicateLine),
        (0usize..4, fields, values()).prop_map(|(l, f, v)| Edit::Field(l, f, v)),
    ]
}

fn apply(text: &str, edit: &Edit) -> Vec<u8> {
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    match edit {
        Edit::Byte(i, b) => {
            let mut bytes = text.as_bytes().to_vec();
            let at = i % bytes.len();
            bytes[at] = *b;
            return bytes;
        }
        Edit::Truncate(i) => return text.as_bytes()[..i % text.len()].to_vec(),
        Edit::DeleteLine(l) => {
            lines.remove(l % lines.len());
        }
        Edit::DuplicateLine(l) => {
            let line = lines[l % lines.len()].clone();
            lines.push(line);
        }
        Edit::Field(l, field, value) => {
            let at = l % lines.len();
            let mut v: Value = serde_json::from_str(&lines[at]).unwrap();
            v[*field] = value.clone();
            lines[at] = v.to_string();
        }
    }
    lines.iter().map(|l| format!("{l}\n")).collect::<String>().into_bytes()
}

/// What a resume does first with the journal: heal a torn last line, then check every record.
fn resume_checks(path: &Path) -> Result<(), String> {
    Journal::heal(path).map_err(|e| e.to_string())?;
    check_journal(path, SIZE_M).map_err(|e| e.to_string())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn any_journal_edit_resumes_to_a_consistent_folder_or_is_refused(edit in edits()) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("journal.jsonl");
        std::fs::write(&path, apply(&journal_text(), &edit)).unwrap();
        match resume_checks(&path) {
            Err(e) => prop_assert!(e.contains("journal.jsonl"), "{e}"),
            Ok(()) => {
                let bytes = std::fs::read(&path).unwrap();
                prop_assert!(bytes.is_empty() || bytes.ends_with(b"\n"), "the next record starts on a line of its own");
                let all = Journal::read_all(&path).unwrap();
                let mut flights = std::collections::HashSet::new();
                for r in &all {
                    prop_assert!(check_record(r, SIZE_M).is_ok(), "{r:?}");
                    prop_assert!(is_inside(&r.trajectory), "{r:?}");
                    if r.charged() {
                        prop_assert!(flights.insert((r.candidate, r.attempt)), "journaled twice: {r:?}");
                    }
                }
                prop_assert_eq!(Journal::read(&path).unwrap().len(), flights.len());
                prop_assert_eq!(Journal::heal(&path).unwrap(), None, "healing twice changes nothing");
            }
        }
    }
}
