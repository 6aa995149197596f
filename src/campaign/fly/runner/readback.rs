//! What a finished job left: a `prgenuav fly --json` report (its stdout or a `.json` file), a PX4 ULog
//! (`*.ulg`, Aerialist's output) or an Aerialist trajectory CSV, found anywhere under its folder. The flight is
//! judged here, from the trajectory, by the campaign's judge edition (as `prgenuav distance` judges a log), so
//! every backend's distances mean the same.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::campaign::fly::vehicle::Flown;
use crate::campaign::ground::flight_status::FlightStatus;
use crate::judge::cp_verdict::{CpVerdict, cp_verdict};
use crate::judge::{Judge, judge_flight};
use crate::model::safe_files::{MAX_READ_BYTES, read_capped};
use crate::model::{Obstacle, Trajectory, load_ulog_trajectory};

/// Folder levels searched below the job folder.
const MAX_DEPTH: usize = 8;
/// Entries looked at, at most: a job that leaves a huge tree is not searched to its end.
const MAX_ENTRIES: usize = 20_000;
/// `.json` files larger than this are not a `fly --json` report and are not read.
const MAX_JSON_BYTES: u64 = 4 << 20;

/// A flight said to have ended whose trajectory ends higher than this above its lowest point did not land.
const ENDS_IN_THE_AIR_M: f64 = 1.0;

/// The part of a `prgenuav fly --json` report the campaign uses (the distances are judged again here).
#[derive(Debug, Clone, Deserialize)]
struct FlyReport {
    status: FlightStatus,
    #[serde(default)]
    reason: Option<String>,
    #[serde(default)]
    warnings: Vec<String>,
    #[serde(default)]
    flight_time_s: Option<f64>,
    /// A Collision Prevention flight's verdict; only its `CP_DIST` is read (the rest is measured again here).
    /// Loose, so a malformed block costs the verdict and not the report.
    #[serde(default)]
    collision_prevention: Option<serde_json::Value>,
}

impl FlyReport {
    /// The `CP_DIST` the job flew, if it was a Collision Prevention flight and says a usable one.
    fn cp_dist_m(&self) -> Option<f64> {
        let d = self.collision_prevention.as_ref()?.get("cp_dist_m")?.as_f64()?;
        (d.is_finite() && d > 0.0).then_some(d)
    }
}

/// A job's flight as read back.
#[derive(Debug, Clone)]
pub struct Readback {
    /// The flight, judged.
    pub flown: Flown,
    /// The judged (origin-aligned) trajectory, if there was one.
    pub trajectory: Option<Trajectory>,
    /// The file it came from.
    pub source: Option<PathBuf>,
    /// Whether a `fly --json` report said how the flight ended.
    pub reported: bool,
}

/// Files found under a job folder, by kind, in the order they are tried.
#[derive(Debug, Default)]
struct Found {
    ulogs: Vec<PathBuf>,
    csvs: Vec<PathBuf>,
    jsons: Vec<PathBuf>,
}

/// Reads back the flight a job left in `dir` (its own inputs `skip` excepted) and on its `stdout`, judged
/// against `obstacles` by `judge`. An error says what was missing or unreadable.
pub fn read_back(
    dir: &Path,
    skip: &[PathBuf],
    stdout: &[u8],
    obstacles: &[Obstacle],
    judge: Judge,
) -> Result<Readback, String> {
    let found = search(dir, skip);
    let report = fly_report(stdout).or_else(|| found.jsons.iter().find_map(|p| json_file(p)));
    let mut problems = Vec::new();
    let trajectory = trajectory(&found, &mut problems);
    match (trajectory, report) {
        (Some((path, t)), report) => {
            let claimed = report.as_ref().map_or(FlightStatus::LANDED, |r| r.status);
            if let Some(why) = not_a_whole_flight(&t, claimed) {
                return Err(format!("{}: {why}", path.display()));
            }
            Ok(judged(t, path, report, obstacles, judge))
        }
        // A flight that ended without a measurement (rejected, link lost) is a result, not a job failure.
        (None, Some(r)) if !r.status.completed() && problems.is_empty() => Ok(Readback {
            flown: Flown {
                flight_time_s: r.flight_time_s.filter(|t| t.is_finite()).unwrap_or(0.0),
                warnings: r.warnings,
                reason: r.reason,
                ..Flown::ended(r.status)
            },
            trajectory: None,
            source: None,
            reported: true,
        }),
        (None, report) => {
            let said = report.map_or(String::new(), |r| {
                format!(
                    " (its fly report says {}, but a report alone cannot be judged)",
                    r.status
                )
            });
            if problems.is_empty() {
                Err(format!(
                    "no trajectory: the job left no flight log (*.ulg) or trajectory CSV (timestamp,x,y,z,r) in {}{said}",
                    dir.display()
                ))
            } else {
                Err(format!("no usable trajectory{said}: {}", problems.join("; ")))
            }
        }
    }
}

/// The first trajectory that reads: ULogs newest first, then trajectory CSVs. Files that look like flights
/// but do not read are listed in `problems`.
fn trajectory(found: &Found, problems: &mut Vec<String>) -> Option<(PathBuf, Trajectory)> {
    for path in &found.ulogs {
        match load_ulog_trajectory(path) {
            Ok(t) => return Some((path.clone(), t)),
            Err(e) => problems.push(e.to_string()),
        }
    }
    for path in &found.csvs {
        let text = match read_capped(path, MAX_READ_BYTES).map(String::from_utf8) {
            Ok(Ok(text)) => text,
            Ok(Err(_)) => {
                problems.push(format!("{}: not UTF-8 text", path.display()));
                continue;
            }
            Err(e) => {
                problems.push(e.to_string());
                continue;
            }
        };
        if !looks_like_trajectory(&text) {
            continue; // a commands or params table, say
        }
        match Trajectory::parse_csv(&text, path) {
            Ok(t) => return Some((path.clone(), t)),
            Err(e) => problems.push(e.to_string()),
        }
    }
    None
}

/// Why `t` cannot be the flight it is `claimed` to be (`landed`, or `collision`: a flight that ended), if it
/// cannot: no time span at all, or an end in the air (a log cut short, which would be judged on half a flight).
fn not_a_whole_flight(t: &Trajectory, claimed: FlightStatus) -> Option<String> {
    let (first, last) = (t.samples.first()?, t.samples.last()?);
    let span = last.t_s - first.t_s;
    if !(span.is_finite() && span > 0.0) {
        return Some(format!(
            "the trajectory has no time span ({} samples, from t = {} s to t = {} s): not a flight",
            t.samples.len(),
            first.t_s,
            last.t_s
        ));
    }
    let lowest = t.samples.iter().map(|s| s.z).fold(f64::INFINITY, f64::min);
    let height = last.z - lowest;
    if claimed.completed() && height > ENDS_IN_THE_AIR_M {
        return Some(format!(
            "the trajectory ends {height:.1} m above its lowest point, at t = {span:.1} s: the flight was cut short \
             (a truncated log), it did not land"
        ));
    }
    None
}

/// Whether a CSV's header names Aerialist's trajectory columns.
fn looks_like_trajectory(text: &str) -> bool {
    let header = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
    let cols: Vec<String> = header.split(',').map(|c| c.trim().to_ascii_lowercase()).collect();
    ["timestamp", "x", "y", "z"].iter().all(|c| cols.iter().any(|h| h == c))
}

/// The flight judged from its trajectory; the fly report, if any, gives the ending and warnings.
fn judged(t: Trajectory, path: PathBuf, report: Option<FlyReport>, obstacles: &[Obstacle], judge: Judge) -> Readback {
    let verdict = judge_flight(&t, obstacles, judge);
    let aligned = t.origin_aligned();
    // Measured on the trajectory judged here, in the same frame as the judged distance.
    let cp: Option<CpVerdict> = report
        .as_ref()
        .and_then(FlyReport::cp_dist_m)
        .map(|d| cp_verdict(&aligned, obstacles, d));
    let reported = report.is_some();
    let (mut status, mut reason, warnings, time) = match report {
        Some(r) => (r.status, r.reason, r.warnings, r.flight_time_s),
        None => (FlightStatus::LANDED, None, Vec::new(), None),
    };
    if let Some(v) = verdict.as_ref().filter(|v| v.collision)
        && matches!(status, FlightStatus::LANDED | FlightStatus::TIMEOUT)
    {
        status = FlightStatus::COLLISION;
        let c = v.closest;
        reason = Some(format!(
            "entered obstacle {} at t = {:.1} s, ({:.2}, {:.2}, {:.2}) m",
            c.obstacle, c.t_s, c.x, c.y, c.z
        ));
    }
    Readback {
        flown: Flown {
            min_distance: verdict.as_ref().map(|v| v.min_distance),
            min_distance_raw: verdict.as_ref().map(|v| v.min_distance_raw),
            flight_time_s: time.filter(|t| t.is_finite()).unwrap_or_else(|| t.duration_s()),
            warnings,
            reason,
            ..Flown::ended(status)
        }
        .with_cp(cp),
        trajectory: Some(aligned),
        source: Some(path),
        reported,
    }
}

/// A `fly --json` report on stdout: the whole of it, or from its first line opening a JSON object.
fn fly_report(stdout: &[u8]) -> Option<FlyReport> {
    let text = std::str::from_utf8(stdout).ok()?;
    let parse = |s: &str| serde_json::from_str::<FlyReport>(s.trim()).ok().filter(known);
    parse(text).or_else(|| {
        let start = text
            .match_indices('\n')
            .map(|(i, _)| i + 1)
            .find(|&i| text[i..].starts_with('{'))?;
        parse(&text[start..])
    })
}

fn json_file(path: &Path) -> Option<FlyReport> {
    let bytes = read_capped(path, MAX_JSON_BYTES).ok()?;
    serde_json::from_slice::<FlyReport>(&bytes).ok().filter(known)
}

fn known(r: &FlyReport) -> bool {
    r.status.from_vehicle()
}

/// Every `.ulg`, `.csv` and `.json` under `dir` but `skip`, bounded in depth and count; ULogs newest first,
/// the rest by path.
fn search(dir: &Path, skip: &[PathBuf]) -> Found {
    let mut found = Found::default();
    let mut ulogs = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), 0usize)];
    let mut seen = 0;
    while let Some((folder, depth)) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for entry in entries.flatten() {
            seen += 1;
            if seen > MAX_ENTRIES {
                break;
            }
            let path = entry.path();
            // Not following links into folders: a job cannot send the search around the disk.
            let Ok(kind) = entry.file_type() else { continue };
            if kind.is_dir() {
                if depth < MAX_DEPTH {
                    stack.push((path, depth + 1));
                }
                continue;
            }
            // Links are not followed either: what is read back lies inside the job's folder.
            if skip.contains(&path) || !kind.is_file() {
                continue;
            }
            let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
            match ext.as_deref() {
                Some("ulg") => {
                    let modified = entry.metadata().and_then(|m| m.modified()).ok();
                    ulogs.push((modified, path));
                }
                Some("csv") => found.csvs.push(path),
                Some("json") => found.jsons.push(path),
                _ => {}
            }
        }
    }
    ulogs.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    found.ulogs = ulogs.into_iter().map(|(_, p)| p).collect();
    found.csvs.sort();
    found.jsons.sort();
    found
}

#[cfg(test)]
#[path = "readback_tests.rs"]
mod tests;
