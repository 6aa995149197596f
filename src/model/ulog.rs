//! Trajectories from PX4 ULog flight logs (`vehicle_local_position`), as Aerialist extracts them.

use std::path::Path;

use px4_ulog::full_parser::{Completeness, ParsedData, SomeVec, read_file};

use super::error::{ModelError, Result};
use super::safe_files::MAX_ULOG_BYTES;
use super::trajectory::{Sample, Trajectory, check_step};
use super::ulog_frames::check_frames;

/// What a damaged log's error adds: it is refused whole, never read as the shorter flight it still holds.
const REFUSED: &str = "refused rather than scored as a shorter flight";

/// A syntax error of the log at `path`.
fn bad(path: &Path, message: String) -> ModelError {
    ModelError::Syntax {
        path: path.to_path_buf(),
        line: None,
        column: None,
        message,
    }
}

/// The log at `path` parsed whole: its framing checked first, and anything the parser had to stop at refused.
fn parse_whole(path: &Path) -> Result<ParsedData> {
    let name = path.to_str().ok_or_else(|| bad(path, "the path is not UTF-8".into()))?;
    check_ulog_file(path)?;
    let frames = check_frames(path).map_err(|source| ModelError::Io {
        path: path.to_path_buf(),
        action: "cannot read",
        source,
    })?;
    if let Err(d) = frames {
        return Err(bad(
            path,
            format!("damaged ULog at byte {}: {}; {REFUSED}", d.offset, d.why),
        ));
    }
    // The parser asserts its own invariants; a malformed log must be an error, not a crash.
    let parsed = std::panic::catch_unwind(|| read_file(name))
        .map_err(|_| bad(path, "malformed ULog (the parser gave up)".into()))?
        .map_err(|e| bad(path, format!("not a readable ULog: {e}")))?;
    match &parsed.completeness {
        Completeness::Complete => Ok(parsed),
        Completeness::Truncated => Err(bad(path, format!("the ULog ends inside a message: {REFUSED}"))),
        Completeness::MalformedRecord(why) => Err(bad(
            path,
            format!("damaged ULog (a message does not parse: {why}); {REFUSED}"),
        )),
    }
}

/// Reads `vehicle_local_position` (first instance) from a ULog: `x` North, `y` East, height = `-z`, heading
/// in radians; time in seconds from the log's first sample. Not yet origin-aligned (the judge does that).
pub fn load_ulog_trajectory(path: &Path) -> Result<Trajectory> {
    let bad = |message: String| bad(path, message);
    let parsed = parse_whole(path)?;
    let topic = parsed
        .messages
        .get("vehicle_local_position")
        .ok_or_else(|| bad("no vehicle_local_position topic in the log".into()))?;
    let mut instances: Vec<_> = topic.iter().collect();
    instances.sort_by_key(|(id, _)| id.value());
    let (_, fields) = instances
        .first()
        .ok_or_else(|| bad("vehicle_local_position has no data".into()))?;
    let column = |name: &str| -> Result<Vec<f64>> {
        match fields.get(name) {
            Some(SomeVec::Float(v)) => Ok(v.iter().map(|x| f64::from(*x)).collect()),
            Some(SomeVec::Double(v)) => Ok(v.clone()),
            Some(SomeVec::UInt64(v)) => Ok(v.iter().map(|x| *x as f64).collect()),
            Some(_) => Err(bad(format!("vehicle_local_position.{name} has an unexpected type"))),
            None => Err(bad(format!("vehicle_local_position has no field {name}"))),
        }
    };
    let (t, x, y, z) = (column("timestamp")?, column("x")?, column("y")?, column("z")?);
    let heading = column("heading").ok();
    let t0 = t
        .first()
        .copied()
        .ok_or_else(|| bad("vehicle_local_position has no samples".into()))?;
    check_timestamps(&t).map_err(bad)?;
    let n = t.len().min(x.len()).min(y.len()).min(z.len());
    let finite = |i: usize| x[i].is_finite() && y[i].is_finite() && z[i].is_finite();
    // Before the estimator has a position the log may hold none; once it has, a gap is damage.
    let from = (0..n).find(|&i| finite(i)).unwrap_or(n);
    if let Some(i) = (from..n).find(|&i| !finite(i)) {
        return Err(bad(format!(
            "vehicle_local_position sample {} (timestamp {} us) has no finite position, after finite ones: {REFUSED}",
            i + 1,
            t[i]
        )));
    }
    let samples = (from..n)
        .map(|i| Sample {
            t_s: (t[i] - t0) / 1e6,
            x: x[i],
            y: y[i],
            z: -z[i],
            r: heading
                .as_ref()
                .and_then(|h| h.get(i).copied())
                .filter(|v| v.is_finite()),
        })
        .collect::<Vec<_>>();
    if samples.is_empty() {
        return Err(bad("vehicle_local_position holds no finite position".into()));
    }
    Ok(Trajectory::new(samples))
}

/// Each `vehicle_local_position` timestamp (microseconds) a valid step from the one before.
fn check_timestamps(t: &[f64]) -> std::result::Result<(), String> {
    for i in 1..t.len() {
        if let Err(why) = check_step(t[i - 1] / 1e6, t[i] / 1e6) {
            return Err(format!(
                "vehicle_local_position sample {} (timestamp {} us) {why}",
                i + 1,
                t[i]
            ));
        }
    }
    Ok(())
}

/// Reads a flight: a ULog (`.ulg`) or an Aerialist trajectory CSV (anything else).
pub fn load_flight(path: &Path) -> Result<Trajectory> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("ulg") => load_ulog_trajectory(path),
        _ => Trajectory::load_csv(path),
    }
}

/// The parser opens the log itself: it gets a regular file within [`MAX_ULOG_BYTES`] only, so a FIFO cannot
/// block it and a device cannot fill memory.
fn check_ulog_file(path: &Path) -> Result<()> {
    let refuse = |source| ModelError::Io {
        path: path.to_path_buf(),
        action: "cannot read",
        source,
    };
    let meta = std::fs::metadata(path).map_err(refuse)?;
    if !meta.is_file() {
        return Err(refuse(std::io::Error::other(
            "not a regular file; only regular files are read",
        )));
    }
    if meta.len() > MAX_ULOG_BYTES {
        return Err(refuse(std::io::Error::other(format!(
            "it is {} bytes; flight logs read are at most {} MiB",
            meta.len(),
            MAX_ULOG_BYTES >> 20
        ))));
    }
    Ok(())
}
