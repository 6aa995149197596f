//! The one trust boundary of a folder a command writes into and reads back: `generate`'s campaign folder,
//! `evaluate`'s `SUITE/evaluation`, `score --averages`. What it writes goes into folders of its own (a link
//! or a file in a folder's place is refused: it would carry every write elsewhere), through the atomic,
//! link-replacing writer; what it reads back is checked before it is believed. A path read from the folder
//! must be a file inside it (no `..`, not absolute, not through a link); a flown distance must be finite and
//! within the arena; times and probabilities must be numbers a flight can have. A line that breaks a rule is
//! refused, naming the line, the field and the rule.

use std::os::unix::fs::MetadataExt;
use std::path::{Component, Path};

use super::journal::{FlightRecord, Journal};
use crate::model::limit::number;
use crate::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};
use crate::model::{Arena, ModelError, TestCase, Trajectory};

/// Creates the folder `dir` if it is missing (its parent must exist), and checks it is a folder of its own
/// ([`check_own_folder`]): `command` names the writer in the refusal.
pub fn make_own_folder(dir: &Path, command: &str) -> Result<(), ModelError> {
    match std::fs::create_dir(dir) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => check_own_folder(dir, command),
        Err(source) => Err(ModelError::Io {
            path: dir.to_path_buf(),
            action: "cannot create",
            source,
        }),
    }
}

/// Checks that `dir`, if there, is a folder and not a link: what `command` writes into must stay inside.
pub fn check_own_folder(dir: &Path, command: &str) -> Result<(), ModelError> {
    let what = match std::fs::symlink_metadata(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(source) => {
            return Err(ModelError::Io {
                path: dir.to_path_buf(),
                action: "cannot inspect",
                source,
            });
        }
        Ok(m) if m.file_type().is_symlink() => match std::fs::read_link(dir) {
            Ok(to) => format!("a link to {}", to.display()),
            Err(_) => "a link".to_string(),
        },
        Ok(m) if m.is_dir() => return Ok(()),
        Ok(_) => "a file".to_string(),
    };
    Err(ModelError::Io {
        path: dir.to_path_buf(),
        action: "cannot write into",
        source: std::io::Error::other(format!(
            "it is {what}, not a folder of its own; {command} writes only inside its folder: remove it, then run \
             again"
        )),
    })
}

/// Whether `a` and `b` are one folder (the same file once links are followed); false if either is missing.
pub fn same_folder(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

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
    if let Some(p) = record.prediction.as_ref().and_then(|p| p.p_fail)
        && !(0.0..=1.0).contains(&p)
    {
        return Err(format!(
            "predicted_p_fail {} is outside [0, 1] (a probability)",
            number(p)
        ));
    }
    Ok(())
}

/// Whether `path` names something inside the folder it is relative to: relative, with plain names only (an
/// empty path, a flight without a file, is inside).
pub fn is_inside(path: &Path) -> bool {
    path.components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir))
}

/// The bytes of the folder's file `relative`: it must be inside `folder` ([`is_inside`]), reached through no
/// link, a regular file within the read cap; else why not.
pub fn read_inside(folder: &Path, relative: &Path) -> Result<Vec<u8>, String> {
    if !is_inside(relative) || relative.as_os_str().is_empty() {
        return Err(format!(
            "{:?} is not a file inside {} (`..` and absolute paths are refused)",
            relative.display().to_string(),
            folder.display()
        ));
    }
    // No link on the way either: `flights` itself may have been replaced by one.
    let mut at = folder.to_path_buf();
    let file = folder.join(relative);
    for part in relative.parent().into_iter().flat_map(Path::components) {
        at.push(part);
        match std::fs::symlink_metadata(&at) {
            Ok(m) if m.is_dir() => {}
            Ok(_) => {
                return Err(format!(
                    "{}: not read: {} is a link or a file, not a folder of its own",
                    file.display(),
                    at.display()
                ));
            }
            Err(_) => {
                return Err(format!(
                    "{}: missing (there is no folder {})",
                    file.display(),
                    at.display()
                ));
            }
        }
    }
    read_capped_no_follow(&folder.join(relative), MAX_READ_BYTES).map_err(|e| e.to_string())
}

/// [`read_inside`], `None` when it cannot be read (the caller goes without it).
pub fn inside_bytes(folder: &Path, relative: &Path) -> Option<Vec<u8>> {
    read_inside(folder, relative).ok()
}

/// The flight (a trajectory CSV) the folder's file `relative` holds, read as [`read_inside`] does; why not,
/// naming the file and where it is damaged.
pub fn read_inside_flight(folder: &Path, relative: &Path) -> Result<Trajectory, String> {
    let bytes = read_inside(folder, relative)?;
    let path = folder.join(relative);
    let text = String::from_utf8(bytes).map_err(|e| {
        format!(
            "{}: not UTF-8 text (invalid byte at offset {})",
            path.display(),
            e.utf8_error().valid_up_to()
        )
    })?;
    Trajectory::parse_csv(&text, &path).map_err(|e| e.to_string())
}

#[cfg(test)]
#[path = "trust_tests.rs"]
mod tests;
