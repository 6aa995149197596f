//! Real PX4 as a second reference: the recorded competition cases flown on PX4 SITL with our companion
//! (`examples/px4_reference.rs`), kept as `flights.csv` + `traj/<id>.csv` so the LFS and the mock can be
//! checked against PX4 without PX4.
//!
//! Distances are re-judged here from the kept trajectories (test frame, 0.5 s bins) with the recorded flights'
//! definition (the 2025 edition, minus the case's definition offset), so they compare with `real_m` and with
//! `fidelity`'s predictions like for like.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::fidelity::FlightCase;
use crate::judge::{Judge, judge_in_frame};
use crate::model::Trajectory;

/// One case as PX4 flew it.
#[derive(Debug, Clone, PartialEq)]
pub struct Px4Flight {
    /// The case's `id`.
    pub id: String,
    /// How the flight ended (`landed`, `timeout`, ...).
    pub status: String,
    /// Minimum distance in the case's definition, re-judged from the kept trajectory; `None` without one.
    pub min_distance: Option<f64>,
    /// Vehicle seconds from takeoff to landing.
    pub flight_time_s: f64,
    /// The companion's 99th percentile answer latency, wall milliseconds (`None` if not recorded).
    pub answer_p99_ms: Option<f64>,
}

/// Why the reference could not be read.
#[derive(Debug, thiserror::Error)]
pub enum Px4FlightsError {
    /// A file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A row is malformed.
    #[error("{path}:{line}: {what}")]
    Row {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        what: String,
    },
}

/// Reads `DIR/flights.csv` and re-judges each flight's `DIR/traj/<id>.csv` against its case in `cases`
/// (rows without a case in `cases` are skipped).
pub fn load(dir: &Path, cases: &[FlightCase]) -> Result<Vec<Px4Flight>, Px4FlightsError> {
    let path = dir.join("flights.csv");
    let text = std::fs::read_to_string(&path).map_err(|source| Px4FlightsError::Io {
        path: path.clone(),
        source,
    })?;
    let by_id: BTreeMap<&str, &FlightCase> = cases.iter().map(|c| (c.id.as_str(), c)).collect();
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = lines.next().map(|(_, h)| h.split(',').collect()).unwrap_or_default();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .ok_or_else(|| Px4FlightsError::Row {
                path: path.clone(),
                line: 1,
                what: format!("no column `{name}`"),
            })
    };
    let (c_id, c_status, c_time, c_p99) = (col("id")?, col("status")?, col("flight_time_s")?, col("answer_p99_ms")?);
    let mut out = Vec::new();
    for (i, line) in lines {
        let f = split_row(line);
        let row_err = |what: String| Px4FlightsError::Row {
            path: path.clone(),
            line: i + 1,
            what,
        };
        let get = |c: usize| f.get(c).map(String::as_str).unwrap_or("");
        let Some(case) = by_id.get(get(c_id)) else { continue };
        let flight_time_s: f64 = get(c_time)
            .parse()
            .map_err(|_| row_err(format!("flight_time_s {:?} is not a number", get(c_time))))?;
        let traj_path = dir.join("traj").join(format!("{}.csv", case.id));
        let min_distance = Trajectory::load_csv(&traj_path)
            .ok()
            .and_then(|t| judge_in_frame(&t, &case.obstacles, Judge::E2025))
            .map(|d| (d.min_distance - case.definition_offset_m).max(0.0));
        out.push(Px4Flight {
            id: case.id.clone(),
            status: get(c_status).to_string(),
            min_distance,
            flight_time_s,
            answer_p99_ms: get(c_p99).parse().ok(),
        });
    }
    Ok(out)
}

/// Splits a CSV row, honouring double-quoted fields (the `reason` column may hold commas).
fn split_row(line: &str) -> Vec<String> {
    let mut out = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                if let Some(s) = out.last_mut() {
                    s.push('"')
                }
            }
            '"' => quoted = !quoted,
            ',' if !quoted => out.push(String::new()),
            c => {
                if let Some(s) = out.last_mut() {
                    s.push(c)
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoted_fields_keep_their_commas_and_quotes() {
        assert_eq!(split_row(r#"a,"b, ""c""",d"#), vec!["a", r#"b, "c""#, "d"]);
        assert_eq!(split_row("x,,y"), vec!["x", "", "y"]);
    }

    #[test]
    fn a_missing_column_names_the_file_and_the_column() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("flights.csv"), "id,status\n").unwrap();
        let e = load(dir.path(), &[]).unwrap_err().to_string();
        assert!(e.contains("flights.csv:1") && e.contains("flight_time_s"), "{e}");
    }
}
