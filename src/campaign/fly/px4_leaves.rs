//! What a `--px4` flight leaves its user beside the trajectory: PX4's console (named in the reason of a flight
//! that did not run to its end) and, with `--keep-ulog`, PX4's ULog.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::bridge::sitl::Px4Sitl;
use crate::campaign::fly::vehicle::Flown;
use crate::campaign::ground::flight_status::FlightStatus;

/// Writes PX4's console beside the trajectory; the path as the journal shows it (`flights/candidate_N.px4.log`),
/// or why it could not be written.
pub(super) fn write_log(path: &Path, log: &str) -> Result<String, String> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    crate::io::write_atomic(path, log.as_bytes()).map_err(|e| e.to_string())?;
    Ok(shown(path).display().to_string())
}

/// `flights/candidate_N.px4.log` of `.../campaign/flights/candidate_N.px4.log`.
fn shown(path: &Path) -> PathBuf {
    let parts: Vec<_> = path.components().collect();
    parts[parts.len().saturating_sub(2)..].iter().collect()
}

pub(super) fn console_note(written: &Result<String, String>) -> String {
    match written {
        Ok(p) => format!("PX4's console: {p}"),
        Err(e) => format!("PX4's console not kept: {e}"),
    }
}

/// A flight that did not run to its end names PX4's console in its reason.
pub(super) fn pointing_to_console(mut f: Flown, written: &Result<String, String>) -> Flown {
    if !f.status.completed() {
        let note = console_note(written);
        f.reason = Some(match f.reason {
            Some(r) => format!("{r}; {note}"),
            None => note,
        });
    }
    f
}

/// The campaign's stop came before the flight took off: `aborted`, which the fleet journals as interrupted.
pub(super) fn stopped_before_flying(written: &Result<String, String>) -> Flown {
    Flown::unflown(
        FlightStatus::ABORTED,
        format!("stopped before PX4 was flying; {}", console_note(written)),
    )
}

/// Copies the instance's newest ULog to `to` (PX4 closes it at disarm, a moment after the landing the bridge
/// saw, so the copy waits until its size settles, bounded).
pub(super) fn keep_ulog(px4: &Px4Sitl, to: &Path, log: &mut String) {
    let Some(newest) = px4.ulogs().pop() else {
        let _ = writeln!(log, "(--keep-ulog: PX4 wrote no ULog)");
        return;
    };
    let size = || std::fs::metadata(&newest).map_or(0, |m| m.len());
    let mut last = size();
    for _ in 0..20 {
        std::thread::sleep(Duration::from_millis(100));
        let now = size();
        if now == last {
            break;
        }
        last = now;
    }
    if let Err(e) = std::fs::copy(&newest, to) {
        let _ = writeln!(
            log,
            "(--keep-ulog: copying {} to {}: {e})",
            newest.display(),
            to.display()
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_console_is_named_relative_to_the_campaign() {
        let p = Path::new("/x/campaign/flights/candidate_4.px4.log");
        assert_eq!(shown(p), PathBuf::from("flights/candidate_4.px4.log"));
        let f = Flown {
            status: FlightStatus::TIMEOUT,
            min_distance: None,
            min_distance_raw: None,
            flight_time_s: 1.0,
            warnings: Vec::new(),
            reason: Some("still flying".into()),
            closest_centre_m: None,
            inside_cp_dist: None,
        };
        let f = pointing_to_console(f, &Ok("flights/candidate_4.px4.log".into()));
        assert_eq!(
            f.reason.as_deref(),
            Some("still flying; PX4's console: flights/candidate_4.px4.log")
        );
    }
}
