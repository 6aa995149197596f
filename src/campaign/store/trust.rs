//! What a journal line may say: the campaign folder is a trust boundary, so a value read back from it is
//! checked before it is believed. A trajectory must be a file inside the folder (no `..`, not absolute, not
//! through a link); a flown distance must be finite and within the arena; times and probabilities must be
//! numbers a flight can have. A line that breaks a rule is refused, naming the line, the field and the rule.

use std::path::{Component, Path};

use super::journal::{FlightRecord, Journal};
use crate::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};
use crate::model::{Arena, ModelError, TestCase};

/// The longest flight time a journal line may state, seconds (a day: far above any flight limit).
pub const MAX_FLIGHT_TIME_S: f64 = 86_400.0;

/// The largest distance anything can be from an obstacle in `case`'s arena, metres: the diagonal of the box
/// holding the obstacle area, every mission position and the tallest allowed box.
pub fn arena_size_m(case: &TestCase) -> f64 {
    let arena = Arena::COMPETITION;
    let (mut x0, mut x1, mut y0, mut y1) = (arena.x.min, arena.x.max, arena.y.min, arena.y.max);
    let mut top = arena.h.max.max(arena.flight_altitude_m);
    for p in case.mission.flight_path() {
        (x0, x1) = (x0.min(p.north_m), x1.max(p.north_m));
        (y0, y1) = (y0.min(p.east_m), y1.max(p.east_m));
        top = top.max(p.alt_m.abs());
    }
    ((x1 - x0).powi(2) + (y1 - y0).powi(2) + top.powi(2)).sqrt()
}

/// Checks every record of the journal at `path` ([`check_record`]; `size_m` is the arena's size): the first
/// line that cannot be believed is an error naming it, and what to do. Errors as [`Journal::read`] too.
pub fn check_journal(path: &Path, size_m: f64) -> Result<(), ModelError> {
    let numbered = Journal::read_numbered(path)?;
    check_lines(numbered.iter().map(|(line, r)| (*line, r)), path, size_m)
}

/// Checks the records `journal` read when it was loaded, as [`check_journal`] does.
pub fn check_loaded(journal: &Journal, size_m: f64) -> Result<(), ModelError> {
    check_lines(journal.numbered(), journal.path(), size_m)
}

fn check_lines<'a>(
    numbered: impl Iterator<Item = (usize, &'a FlightRecord)>,
    path: &Path,
    size_m: f64,
) -> Result<(), ModelError> {
    for (line, record) in numbered {
        check_record(record, size_m).map_err(|why| ModelError::Syntax {
            path: path.to_path_buf(),
            line: Some(line),
            column: None,
            message: format!(
                "{why}; the journal was edited or damaged: delete this line (its flight is flown again) or \
                 restore the journal, then resume"
            ),
        })?;
    }
    Ok(())
}

/// Why `record` cannot be believed, if it cannot: `size_m` is the arena's size ([`arena_size_m`]).
pub fn check_record(record: &FlightRecord, size_m: f64) -> Result<(), String> {
    if !is_inside(&record.trajectory) {
        return Err(format!(
            "trajectory {:?} is not a file inside the campaign folder (a journal names flights/candidate_K.csv; \
             `..` and absolute paths are refused)",
            record.trajectory.display().to_string()
        ));
    }
    for (field, d) in [
        ("min_distance", record.flown.min_distance),
        ("min_distance_raw", record.flown.min_distance_raw),
        ("closest_centre_m", record.flown.closest_centre_m),
    ] {
        if let Some(d) = d
            && !(d.is_finite() && (0.0..=size_m).contains(&d))
        {
            return Err(format!(
                "{field} {} m is outside [0, {size_m:.1}] m (a distance within the arena)",
                number(d)
            ));
        }
    }
    let times = [("flight_time_s", record.flown.flight_time_s), ("wall_s", record.wall_s)];
    for (field, t) in times {
        if !(t.is_finite() && (0.0..=MAX_FLIGHT_TIME_S).contains(&t)) {
            return Err(format!("{field} {} s is outside [0, {MAX_FLIGHT_TIME_S}] s", number(t)));
        }
    }
    if let Some(p) = record.prediction.p_fail
        && !(0.0..=1.0).contains(&p)
    {
        return Err(format!(
            "predicted_p_fail {} is outside [0, 1] (a probability)",
            number(p)
        ));
    }
    Ok(())
}

/// A number as a user reads it: huge ones in scientific notation, not three hundred digits.
fn number(v: f64) -> String {
    if v.is_finite() && v.abs() >= 1e6 {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Whether `path` names something inside the folder it is relative to: relative, with plain names only (an
/// empty path, a flight without a file, is inside).
pub fn is_inside(path: &Path) -> bool {
    path.components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
}

/// The bytes of the folder's file `relative`, if it is inside `folder` ([`is_inside`]), a regular file and no
/// link, and within the read cap; `None` otherwise (the caller goes without it).
pub fn inside_bytes(folder: &Path, relative: &Path) -> Option<Vec<u8>> {
    if !is_inside(relative) || relative.as_os_str().is_empty() {
        return None;
    }
    // No link on the way either: `flights` itself may have been replaced by one.
    let mut at = folder.to_path_buf();
    for part in relative.parent().into_iter().flat_map(Path::components) {
        at.push(part);
        if std::fs::symlink_metadata(&at).map_or(true, |m| !m.is_dir()) {
            return None;
        }
    }
    read_capped_no_follow(&folder.join(relative), MAX_READ_BYTES).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::campaign::store::journal::test_record;

    #[test]
    fn paths_leaving_the_folder_are_not_inside() {
        for p in ["flights/candidate_1.csv", "./flights/x.csv", ""] {
            assert!(is_inside(Path::new(p)), "{p}");
        }
        for p in ["../x.csv", "flights/../../etc/passwd", "/etc/passwd"] {
            assert!(!is_inside(Path::new(p)), "{p}");
        }
    }

    #[test]
    fn distances_outside_the_arena_and_odd_times_are_refused() {
        let ok = test_record(1, 1.0, Some(2.0));
        check_record(&ok, 100.0).unwrap();
        for d in [-1.0, 1e300, 100.5] {
            let e = check_record(&test_record(1, 1.0, Some(d)), 100.0).unwrap_err();
            assert!(e.contains("min_distance") && e.contains("outside [0, 100.0]"), "{e}");
        }
        let mut slow = ok.clone();
        slow.flown.flight_time_s = -3.0;
        assert!(check_record(&slow, 100.0).unwrap_err().contains("flight_time_s"));
        let away = FlightRecord {
            trajectory: "../../../../etc/hosts".into(),
            ..ok
        };
        let e = check_record(&away, 100.0).unwrap_err();
        assert!(
            e.contains("../../../../etc/hosts") && e.contains("not a file inside"),
            "{e}"
        );
    }

    #[test]
    fn a_link_inside_the_folder_is_not_read_through() {
        let dir = tempfile::tempdir().unwrap();
        let secret = dir.path().join("secret");
        std::fs::write(&secret, "s").unwrap();
        std::fs::create_dir(dir.path().join("f")).unwrap();
        std::os::unix::fs::symlink(&secret, dir.path().join("f/l.csv")).unwrap();
        std::fs::write(dir.path().join("f/r.csv"), "r").unwrap();
        assert_eq!(inside_bytes(dir.path(), Path::new("f/l.csv")), None);
        assert_eq!(inside_bytes(dir.path(), Path::new("f/r.csv")), Some(b"r".to_vec()));
        assert_eq!(inside_bytes(dir.path(), Path::new("f/../secret")), None);
        std::os::unix::fs::symlink(dir.path().join("f"), dir.path().join("g")).unwrap();
        assert_eq!(inside_bytes(dir.path(), Path::new("g/r.csv")), None, "a linked folder");
    }
}
