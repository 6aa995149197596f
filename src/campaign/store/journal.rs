//! The campaign's journal: one JSON line per finished flight, synced to disk before anything else happens,
//! so a killed campaign can resume without flying a test twice.

use std::collections::{HashMap, HashSet};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::campaign::ground::candidate::LfsPrediction;
use crate::campaign::ground::candidate_id::CandidateId;
use crate::campaign::ground::flight_status::{FlightStatus, Flown};
use crate::io::write_atomic;
use crate::model::safe_files::{MAX_READ_BYTES, open_append_no_follow, read_capped};
use crate::model::{ModelError, Obstacle};

/// One finished flight: the candidate's prediction and the vehicle's outcome as they are, with where and how
/// long it flew. Written as one journal line (`store/journal_line.rs` spells its shape).
#[derive(Debug, Clone, PartialEq)]
pub struct FlightRecord {
    /// The candidate flown.
    pub candidate: CandidateId,
    /// Which flight of the candidate this is, from 0: a failing test is flown again to confirm it
    /// (`--confirm`). Left out of the line when 0, so journals without re-flights read and write as before.
    pub attempt: u32,
    /// Its obstacles.
    pub obstacles: Vec<Obstacle>,
    /// The prediction it was flown on (`None`: flown unscreened, or as written). Read back from the journal
    /// it has the journaled fields (distance, flight time, failure probability, the LFS's own distance), not
    /// the LFS's status or expected points.
    pub prediction: Option<LfsPrediction>,
    /// How the flight ended, as the vehicle reported it.
    pub flown: Flown,
    /// The vehicle (MAVLink URL or `mock`) that flew it.
    pub vehicle: String,
    /// The trajectory CSV, relative to the campaign folder.
    pub trajectory: PathBuf,
    /// Wall-clock seconds the flight took.
    pub wall_s: f64,
}

impl FlightRecord {
    /// The LFS's predicted minimum distance, metres, if it predicted the flight.
    pub fn predicted_m(&self) -> Option<f64> {
        self.prediction.as_ref().map(|p| p.min_distance)
    }

    /// Whether the flight counts against the budget (and is a flight the campaign learns from and reports).
    pub fn charged(&self) -> bool {
        self.flown.status.charged()
    }
}

/// A test's first flight (serde leaves its `attempt` out).
pub(crate) fn is_first(attempt: &u32) -> bool {
    *attempt == 0
}

/// The flights of `records` charged to the budget. Every budget count goes through here.
pub fn flights_charged(records: &[FlightRecord]) -> usize {
    records.iter().filter(|r| r.charged()).count()
}

/// An append-only JSONL journal.
#[derive(Debug)]
pub struct Journal {
    path: PathBuf,
    file: File,
    /// Every record, as read when loaded ([`Self::load`]) and appended since.
    pub(super) records: Vec<FlightRecord>,
    /// The line numbers of the records read when loaded.
    pub(super) lines: Vec<usize>,
}

impl Journal {
    /// Opens (creating if needed) the journal at `path` for appending.
    pub fn open(path: &Path) -> Result<Self, ModelError> {
        // A link planted in place of the journal is refused, not appended through.
        let file = open_append_no_follow(path).map_err(|source| ModelError::Io {
            path: path.to_path_buf(),
            action: "cannot open for appending",
            source,
        })?;
        Ok(Self {
            path: path.to_path_buf(),
            file,
            records: Vec::new(),
            lines: Vec::new(),
        })
    }

    /// Where the journal is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends one record and syncs it to disk before returning; the records in memory get it as the file
    /// reads it back.
    pub fn append(&mut self, record: &FlightRecord) -> Result<(), ModelError> {
        let io = |source| ModelError::Io {
            path: self.path.clone(),
            action: "cannot append to",
            source,
        };
        let mut line = serde_json::to_string(record).map_err(|e| io(std::io::Error::other(e)))?;
        line.push('\n');
        self.file.write_all(line.as_bytes()).map_err(io)?;
        self.file.sync_data().map_err(io)?;
        self.records.push(Self::read_back(record));
        Ok(())
    }

    /// `record` as [`Self::read`] gives it back (a non-finite optional distance is stored as `null`), so a
    /// campaign keeping its journal in memory sees what a resumed one reads.
    pub fn read_back(record: &FlightRecord) -> FlightRecord {
        serde_json::to_string(record)
            .ok()
            .and_then(|line| serde_json::from_str(&line).ok())
            .unwrap_or_else(|| record.clone())
    }

    /// Reads the flights charged to the budget, the ones a campaign learns from and reports (not those
    /// [`FlightStatus::charged`]). A torn last line (no newline, not a record: the process died mid-write) is left out, as
    /// [`Self::heal`] drops it; a damaged line elsewhere, or a flight (candidate and attempt) journaled twice,
    /// is an error.
    pub fn read(path: &Path) -> Result<Vec<FlightRecord>, ModelError> {
        Ok(Self::read_all(path)?
            .into_iter()
            .filter(FlightRecord::charged)
            .collect())
    }

    /// Reads every record, charged or not, in journal order. Errors as [`Self::read`].
    pub fn read_all(path: &Path) -> Result<Vec<FlightRecord>, ModelError> {
        Ok(parse(&read_bytes(path)?, path)?.records)
    }

    /// The interrupted flights still to fly: the last interrupted record of each candidate that has no charged
    /// flight, in journal order.
    pub fn interrupted(path: &Path) -> Result<Vec<FlightRecord>, ModelError> {
        let all = Self::read_all(path)?;
        let charged: HashSet<CandidateId> = all.iter().filter(|r| r.charged()).map(|r| r.candidate).collect();
        let mut pending: Vec<FlightRecord> = Vec::new();
        for r in all
            .into_iter()
            .filter(|r| r.flown.status == FlightStatus::Interrupted && !charged.contains(&r.candidate))
        {
            pending.retain(|p| p.candidate != r.candidate);
            pending.push(r);
        }
        Ok(pending)
    }

    /// Every record with its line number, in journal order (errors as [`Self::read`]): for checks that name
    /// the line.
    pub fn read_numbered(path: &Path) -> Result<Vec<(usize, FlightRecord)>, ModelError> {
        let parsed = parse(&read_bytes(path)?, path)?;
        Ok(parsed.lines.into_iter().zip(parsed.records).collect())
    }

    /// Drops a torn last line (or ends a complete one with its newline) by rewriting the journal whole, so
    /// the next record starts on a line of its own; says what was dropped, for the user. Errors as
    /// [`Self::read`].
    pub fn heal(path: &Path) -> Result<Option<String>, ModelError> {
        let bytes = read_bytes(path)?;
        let parsed = parse(&bytes, path)?;
        let Some(tail) = parsed.unterminated else {
            return Ok(None);
        };
        let (kept, message) = healed(&bytes, tail, parsed.torn, path);
        write_atomic(path, &kept)?;
        Ok(message)
    }
}

/// The journal `bytes` whose last line starts at `tail` and has no newline, healed: that line dropped when it is
/// `torn` (its number), else ended; and what was dropped, for the user.
pub(super) fn healed(bytes: &[u8], tail: usize, torn: Option<usize>, path: &Path) -> (Vec<u8>, Option<String>) {
    match torn {
        Some(line) => {
            let dropped = String::from_utf8_lossy(&bytes[tail..]);
            let preview: String = dropped.chars().take(60).collect();
            let message = format!(
                "{}:{line}: dropped a torn last line ({} bytes, {preview:?}...): the flight being written when \
                 the campaign stopped; it is flown again",
                path.display(),
                bytes.len() - tail
            );
            (bytes[..tail].to_vec(), Some(message))
        }
        None => ([bytes, b"\n"].concat(), None),
    }
}

/// The journal's bytes; none when there is no journal yet.
pub(super) fn read_bytes(path: &Path) -> Result<Vec<u8>, ModelError> {
    #[cfg(test)]
    READS.with(|n| n.set(n.get() + 1));
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
        _ => read_capped(path, MAX_READ_BYTES),
    }
}

#[cfg(test)]
thread_local! {
    /// How many times this thread read a journal file: a run reads it once.
    pub(in crate::campaign) static READS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// A journal's records, checked line by line.
pub(super) struct Parsed {
    pub(super) records: Vec<FlightRecord>,
    /// Each record's line number.
    pub(super) lines: Vec<usize>,
    /// Where the last line starts when it has no newline.
    pub(super) unterminated: Option<usize>,
    /// That line's number when it is not a record (a torn write).
    pub(super) torn: Option<usize>,
}

pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<Parsed, ModelError> {
    let syntax = |line: usize, message: String| ModelError::Syntax {
        path: path.to_path_buf(),
        line: Some(line),
        column: None,
        message,
    };
    let mut parsed = Parsed {
        records: Vec::new(),
        lines: Vec::new(),
        unterminated: None,
        torn: None,
    };
    let mut lines_of: HashMap<(CandidateId, u32), usize> = HashMap::new();
    let mut offset = 0;
    for (i, line) in bytes.split(|b| *b == b'\n').enumerate() {
        let (number, start) = (i + 1, offset);
        offset += line.len() + 1;
        let last = offset > bytes.len();
        if last && !line.is_empty() {
            parsed.unterminated = Some(start);
        }
        if line.trim_ascii().is_empty() {
            continue;
        }
        let record = match record_of(line) {
            Ok(r) => r,
            Err(_) if last => {
                parsed.torn = Some(number);
                break;
            }
            Err(e) => {
                return Err(syntax(
                    number,
                    format!(
                        "not a journal record ({e}); only a torn last line is dropped on resume: delete this \
                         line (its flight is flown again) or restore the journal, then resume"
                    ),
                ));
            }
        };
        if record.charged()
            && let Some(first) = lines_of.insert((record.candidate, record.attempt), number)
        {
            return Err(syntax(number, journaled_twice(&record, first, number)));
        }
        parsed.records.push(record);
        parsed.lines.push(number);
    }
    Ok(parsed)
}

/// One line as a record, or why it is not one.
fn record_of(line: &[u8]) -> Result<FlightRecord, String> {
    let text = std::str::from_utf8(line).map_err(|e| e.to_string())?;
    serde_json::from_str::<FlightRecord>(text).map_err(|e| e.to_string())
}

/// Why a flight journaled on line `first` and again on `again` is refused, and the fix.
fn journaled_twice(record: &FlightRecord, first: usize, again: usize) -> String {
    let flight = match record.attempt {
        0 => String::new(),
        a => format!(" (flight {})", a + 1),
    };
    format!(
        "candidate {}{flight} is journaled twice (lines {first} and {again}); a flight is journaled once: delete \
         one of the two lines, then resume",
        record.candidate
    )
}

/// A landed flight with no obstacles for tests: `raw` predicted, `flown` measured.
#[cfg(test)]
pub(crate) fn test_record(candidate: u64, raw: f64, flown: Option<f64>) -> FlightRecord {
    FlightRecord {
        candidate: CandidateId(candidate),
        attempt: 0,
        obstacles: Vec::new(),
        prediction: Some(LfsPrediction {
            raw_min_distance: Some(raw),
            ..LfsPrediction::point(CandidateId(candidate), raw, 60.0, String::new())
        }),
        flown: Flown {
            min_distance: flown,
            min_distance_raw: flown,
            flight_time_s: 60.0,
            ..Flown::ended(FlightStatus::LANDED)
        },
        vehicle: "x".into(),
        trajectory: "t.csv".into(),
        wall_s: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs::OpenOptions;

    pub(in crate::campaign) fn record(candidate: u64) -> FlightRecord {
        FlightRecord {
            candidate: CandidateId(candidate),
            attempt: 0,
            obstacles: vec![Obstacle::new(2.0, 2.0, 20.0, 0.0, 20.0, 0.0)],
            prediction: Some(LfsPrediction::point(CandidateId(candidate), 0.5, 40.0, String::new())),
            flown: Flown {
                min_distance: Some(1.0),
                min_distance_raw: Some(0.9),
                flight_time_s: 41.0,
                ..Flown::ended(FlightStatus::LANDED)
            },
            vehicle: "mock".into(),
            trajectory: "flights/candidate_1.csv".into(),
            wall_s: 0.3,
        }
    }

    pub(in crate::campaign) fn line(candidate: u64) -> String {
        serde_json::to_string(&record(candidate)).unwrap() + "\n"
    }

    #[test]
    fn append_and_read_back_ignoring_a_torn_last_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("journal.jsonl");
        let mut j = Journal::open(&path).unwrap();
        j.append(&record(1)).unwrap();
        j.append(&record(7)).unwrap();
        drop(j);
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(b"{\"candidate\": 9, \"obst").unwrap();
        let back = Journal::read(&path).unwrap();
        assert_eq!(back, vec![record(1), record(7)]);
        assert!(Journal::read(&dir.path().join("none.jsonl")).unwrap().is_empty());
    }

    #[test]
    fn a_stop_reason_is_kept_and_older_lines_read_without_one() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("journal.jsonl");
        let base = record(2);
        let stopped = FlightRecord {
            flown: Flown {
                status: FlightStatus::LINK_LOST,
                reason: Some("no MISSION_ACK within 1.0 s".into()),
                min_distance: None,
                ..base.flown.clone()
            },
            ..base
        };
        let mut j = Journal::open(&path).unwrap();
        j.append(&stopped).unwrap();
        drop(j);
        assert_eq!(Journal::read(&path).unwrap(), vec![stopped]);
        let old = serde_json::to_string(&record(1)).unwrap();
        assert!(!old.contains("reason"), "{old}");
        std::fs::write(&path, format!("{old}\n")).unwrap();
        assert_eq!(Journal::read(&path).unwrap()[0].flown.reason, None);
    }

    #[test]
    fn a_corrupt_middle_line_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("journal.jsonl");
        let good = serde_json::to_string(&record(1)).unwrap();
        std::fs::write(&path, format!("{good}\nnot json\n{good}\n")).unwrap();
        let e = Journal::read(&path).unwrap_err().to_string();
        assert!(e.contains("journal.jsonl:2"), "{e}");
    }
}

#[cfg(test)]
#[path = "journal_tests.rs"]
mod journal_tests;
