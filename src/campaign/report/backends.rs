//! The report's per-backend figures: flights, failed jobs and wall time per flight of each kind of vehicle,
//! read from the journal's `vehicle` names (`mock#0`, `px4#1`, `runner#2`, or a MAVLink URL).

use std::fmt::Write as _;

use serde::Serialize;

use crate::campaign::ground::flight_status::FlightStatus;
use crate::campaign::store::journal::FlightRecord;

/// One backend's flights.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BackendSummary {
    /// `mock`, `px4`, `runner` (the name before `#`), or the MAVLink URL.
    pub backend: String,
    /// Flights charged to the budget.
    pub flights: usize,
    /// Flights its backend failed around after the retry (`backend_failed`, not charged).
    pub failed_jobs: usize,
    /// Median wall time of its charged flights, seconds (retries included).
    pub median_wall_s: Option<f64>,
}

/// The backend a journaled vehicle name belongs to: `runner#3` is `runner`, a URL is itself.
pub fn backend_of(vehicle: &str) -> &str {
    match vehicle.split_once('#') {
        Some((kind, n)) if !kind.is_empty() && n.chars().all(|c| c.is_ascii_digit()) => kind,
        _ => vehicle,
    }
}

/// Per backend, in order of first flight, over every journaled record (charged or not).
pub fn summarise(records: &[FlightRecord]) -> Vec<BackendSummary> {
    let mut names: Vec<&str> = Vec::new();
    for r in records {
        let b = backend_of(&r.vehicle);
        if !names.contains(&b) {
            names.push(b);
        }
    }
    names
        .into_iter()
        .map(|name| {
            let mine: Vec<&FlightRecord> = records.iter().filter(|r| backend_of(&r.vehicle) == name).collect();
            let mut walls: Vec<f64> = mine.iter().filter(|r| r.charged()).map(|r| r.wall_s).collect();
            walls.sort_by(f64::total_cmp);
            BackendSummary {
                backend: name.to_string(),
                flights: walls.len(),
                failed_jobs: mine
                    .iter()
                    .filter(|r| r.flown.status == FlightStatus::BackendFailed)
                    .count(),
                median_wall_s: median(&walls),
            }
        })
        .collect()
}

fn median(sorted: &[f64]) -> Option<f64> {
    let n = sorted.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(sorted[n / 2]),
        _ => Some((sorted[n / 2 - 1] + sorted[n / 2]) / 2.0),
    }
}

/// The report.md table.
pub fn markdown(md: &mut String, backends: &[BackendSummary]) {
    if backends.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "| backend | flights | failed jobs (backend_failed, not charged) | median wall time per flight |\n|---|---|---|---|"
    );
    for b in backends {
        let wall = b.median_wall_s.map_or("-".into(), |w| format!("{w:.2} s"));
        let _ = writeln!(md, "| {} | {} | {} | {wall} |", b.backend, b.flights, b.failed_jobs);
    }
    md.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::fly::vehicle::Flown;
    use crate::campaign::ground::candidate::{CandidateId, LfsPrediction};

    fn record(vehicle: &str, status: FlightStatus, wall_s: f64) -> FlightRecord {
        FlightRecord {
            candidate: CandidateId(0),
            obstacles: Vec::new(),
            prediction: Some(LfsPrediction::point(CandidateId(0), 1.0, 1.0, String::new())),
            flown: Flown {
                flight_time_s: 1.0,
                ..Flown::ended(status)
            },
            vehicle: vehicle.into(),
            trajectory: "x.csv".into(),
            wall_s,
            attempt: 0,
        }
    }

    #[test]
    fn vehicles_are_grouped_by_kind() {
        assert_eq!(backend_of("runner#12"), "runner");
        assert_eq!(backend_of("px4#0"), "px4");
        assert_eq!(backend_of("udpin:0.0.0.0:14540"), "udpin:0.0.0.0:14540");
        assert_eq!(backend_of("a#b"), "a#b");
        let s = summarise(&[
            record("runner#0", FlightStatus::LANDED, 3.0),
            record("mock#1", FlightStatus::LANDED, 0.5),
            record("runner#1", FlightStatus::BackendFailed, 99.0),
            record("runner#1", FlightStatus::COLLISION, 5.0),
            record("runner#0", FlightStatus::Interrupted, 1.0),
        ]);
        assert_eq!(s.len(), 2);
        assert_eq!(
            (s[0].backend.as_str(), s[0].flights, s[0].failed_jobs),
            ("runner", 2, 1)
        );
        assert_eq!(s[0].median_wall_s, Some(4.0));
        assert_eq!(
            (s[1].backend.as_str(), s[1].flights, s[1].median_wall_s),
            ("mock", 1, Some(0.5))
        );
        let mut md = String::new();
        markdown(&mut md, &s);
        assert!(md.contains("| runner | 2 | 1 | 4.00 s |"), "{md}");
    }
}
