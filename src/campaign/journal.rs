//! The campaign's journal: one JSON line per finished flight, synced to disk before anything else happens,
//! so a killed campaign can resume without flying a test twice.

use std::fs::{File, OpenOptions};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::model::{ModelError, Obstacle};

/// One finished flight.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlightRecord {
    /// The candidate's index (its generator index for the campaign's seed).
    pub candidate: u64,
    /// Its obstacles.
    pub obstacles: Vec<Obstacle>,
    /// The LFS's predicted minimum distance, metres.
    pub predicted_min_distance: f64,
    /// The LFS's predicted flight time, seconds.
    pub predicted_flight_time_s: f64,
    /// The LFS ensemble's probability of a flight below 1.5 m (absent without an ensemble).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub predicted_p_fail: Option<f64>,
    /// The LFS's own prediction when `predicted_min_distance` is calibrated (a learning campaign), metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub predicted_raw_min_distance: Option<f64>,
    /// The flown minimum distance (competition definition), metres; `None` if nothing usable was recorded.
    pub min_distance: Option<f64>,
    /// The flown un-binned minimum distance, metres.
    pub min_distance_raw: Option<f64>,
    /// How the flight ended (`landed`, `collision`, `timeout`, `link_lost`, `aborted`, `rejected`, ...).
    pub status: String,
    /// Flight time, seconds.
    pub flight_time_s: f64,
    /// Warnings of the flight side (e.g. the avoidance planner falling behind).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Why the flight stopped, in words, when it did not land (optional: journals without it still resume).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The vehicle (MAVLink URL or `mock`) that flew it.
    pub vehicle: String,
    /// The trajectory CSV, relative to the campaign folder.
    pub trajectory: PathBuf,
    /// Wall-clock seconds the flight took.
    pub wall_s: f64,
}

/// An append-only JSONL journal.
#[derive(Debug)]
pub struct Journal {
    path: PathBuf,
    file: File,
}

impl Journal {
    /// Opens (creating if needed) the journal at `path` for appending.
    pub fn open(path: &Path) -> Result<Self, ModelError> {
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|source| ModelError::Io {
                path: path.to_path_buf(),
                action: "cannot open for appending",
                source,
            })?;
        Ok(Self {
            path: path.to_path_buf(),
            file,
        })
    }

    /// Where the journal is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends one record and syncs it to disk before returning.
    pub fn append(&mut self, record: &FlightRecord) -> Result<(), ModelError> {
        let io = |source| ModelError::Io {
            path: self.path.clone(),
            action: "cannot append to",
            source,
        };
        let mut line = serde_json::to_string(record).map_err(|e| io(std::io::Error::other(e)))?;
        line.push('\n');
        self.file.write_all(line.as_bytes()).map_err(io)?;
        self.file.sync_data().map_err(io)
    }

    /// `record` as [`Self::read`] gives it back (a non-finite optional distance is stored as `null`), so a
    /// campaign keeping its journal in memory sees what a resumed one reads.
    pub fn read_back(record: &FlightRecord) -> FlightRecord {
        serde_json::to_string(record)
            .ok()
            .and_then(|line| serde_json::from_str(&line).ok())
            .unwrap_or_else(|| record.clone())
    }

    /// Reads every complete record; a torn last line (the process died mid-write) is ignored.
    pub fn read(path: &Path) -> Result<Vec<FlightRecord>, ModelError> {
        let file = match File::open(path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
            Err(source) => {
                return Err(ModelError::Io {
                    path: path.to_path_buf(),
                    action: "cannot read",
                    source,
                });
            }
        };
        let lines: Vec<String> = BufReader::new(file)
            .lines()
            .collect::<Result<_, _>>()
            .map_err(|source| ModelError::Io {
                path: path.to_path_buf(),
                action: "cannot read",
                source,
            })?;
        let mut out = Vec::new();
        for (i, line) in lines.iter().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            match serde_json::from_str::<FlightRecord>(line) {
                Ok(r) => out.push(r),
                Err(_) if i + 1 == lines.len() => break, // torn final write
                Err(e) => {
                    return Err(ModelError::Syntax {
                        path: path.to_path_buf(),
                        line: Some(i + 1),
                        column: None,
                        message: format!("not a journal record: {e}"),
                    });
                }
            }
        }
        Ok(out)
    }
}

/// A landed flight with no obstacles for tests: `raw` predicted, `flown` measured.
#[cfg(test)]
pub(crate) fn test_record(candidate: u64, raw: f64, flown: Option<f64>) -> FlightRecord {
    FlightRecord {
        candidate,
        obstacles: Vec::new(),
        predicted_min_distance: raw,
        predicted_flight_time_s: 60.0,
        predicted_p_fail: None,
        predicted_raw_min_distance: Some(raw),
        min_distance: flown,
        min_distance_raw: flown,
        status: "landed".into(),
        flight_time_s: 60.0,
        warnings: Vec::new(),
        reason: None,
        vehicle: "x".into(),
        trajectory: "t.csv".into(),
        wall_s: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(candidate: u64) -> FlightRecord {
        FlightRecord {
            candidate,
            obstacles: vec![Obstacle::new(2.0, 2.0, 20.0, 0.0, 20.0, 0.0)],
            predicted_min_distance: 0.5,
            predicted_flight_time_s: 40.0,
            predicted_p_fail: None,
            predicted_raw_min_distance: None,
            min_distance: Some(1.0),
            min_distance_raw: Some(0.9),
            status: "landed".into(),
            flight_time_s: 41.0,
            warnings: Vec::new(),
            reason: None,
            vehicle: "mock".into(),
            trajectory: "flights/candidate_1.csv".into(),
            wall_s: 0.3,
        }
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
        let stopped = FlightRecord {
            status: "link_lost".into(),
            reason: Some("no MISSION_ACK within 1.0 s".into()),
            min_distance: None,
            ..record(2)
        };
        let mut j = Journal::open(&path).unwrap();
        j.append(&stopped).unwrap();
        drop(j);
        assert_eq!(Journal::read(&path).unwrap(), vec![stopped]);
        let old = serde_json::to_string(&record(1)).unwrap();
        assert!(!old.contains("reason"), "{old}");
        std::fs::write(&path, format!("{old}\n")).unwrap();
        assert_eq!(Journal::read(&path).unwrap()[0].reason, None);
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
