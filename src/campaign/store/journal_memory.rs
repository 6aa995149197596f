//! The journal kept in memory: a run reads the file once, when it opens it, and every flight it appends is added
//! to the records as the file would read it back. Every stage of the run asks here, not the file.

use std::collections::HashSet;
use std::path::Path;

use super::journal::{FlightRecord, Journal, healed, parse, read_bytes};
use crate::campaign::ground::candidate_id::CandidateId;
use crate::campaign::ground::flight_status::FlightStatus;
use crate::io::write_atomic;
use crate::model::ModelError;

impl Journal {
    /// Reads the journal at `path` (none yet: empty) once, drops a torn last line as [`Self::heal`] does, and
    /// opens it for appending; says what was dropped, for the user. Errors as [`Self::read`].
    pub fn load(path: &Path) -> Result<(Self, Option<String>), ModelError> {
        let bytes = read_bytes(path)?;
        let parsed = parse(&bytes, path)?;
        let dropped = match parsed.unterminated {
            Some(tail) => {
                let (kept, message) = healed(&bytes, tail, parsed.torn, path);
                write_atomic(path, &kept)?;
                message
            }
            None => None,
        };
        let mut journal = Self::open(path)?;
        journal.records = parsed.records;
        journal.lines = parsed.lines;
        Ok((journal, dropped))
    }

    /// Every record, charged or not, in journal order.
    pub fn records(&self) -> &[FlightRecord] {
        &self.records
    }

    /// The flights charged to the budget, in journal order (what [`Self::read`] gives).
    pub fn charged(&self) -> Vec<FlightRecord> {
        self.records.iter().filter(|r| r.charged()).cloned().collect()
    }

    /// The records read when the journal was loaded, each with its line number: for checks that name the line.
    pub fn numbered(&self) -> impl Iterator<Item = (usize, &FlightRecord)> {
        self.lines.iter().copied().zip(&self.records)
    }

    /// The interrupted flights still to fly: the last interrupted record of each candidate that has no charged
    /// flight, in journal order.
    pub fn pending_interrupted(&self) -> Vec<FlightRecord> {
        let charged: HashSet<CandidateId> = self
            .records
            .iter()
            .filter(|r| r.charged())
            .map(|r| r.candidate)
            .collect();
        let mut pending: Vec<FlightRecord> = Vec::new();
        for r in (self.records.iter())
            .filter(|r| r.flown.status == FlightStatus::Interrupted && !charged.contains(&r.candidate))
        {
            pending.retain(|p| p.candidate != r.candidate);
            pending.push(r.clone());
        }
        pending
    }
}
