//! A campaign folder has one writer: a new campaign gets a folder of its own (a suffix rather than sharing one
//! with a campaign started in the same second), and the campaign writing it holds an advisory lock that a
//! second `generate` or `--resume` on the folder is refused by. The kernel drops the lock when its holder dies,
//! even by `kill -9`, so a crashed campaign never blocks its own resume.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::ErrorKind;
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

use crate::campaign::ground::error::CampaignError;
use crate::model::safe_files::read_capped;
use crate::model::{ModelError, write_atomic};

/// The file inside a campaign folder that holds the writer's process id (the lock is on the folder).
pub const LOCK_FILE: &str = "campaign.lock";

/// How long a held lock is waited for before refusing. A process that spawns a child shares the lock file
/// with it between its fork and its exec (close-on-exec closes it only at the exec), so a lock just released
/// can stay held for that moment.
const LOCK_PATIENCE: Duration = Duration::from_millis(1500);
const LOCK_POLL: Duration = Duration::from_millis(25);

/// Suffixes tried after the timestamp itself (`-2`, `-3`, ...): far more campaigns than start in one second.
const MAX_SUFFIX: u32 = 1000;

/// Creates a new, empty campaign folder `DIR/<YYYY-MM-DDTHH-MM-SS>` for `now`, or with `-2`, `-3`, ... when a
/// campaign started in the same second already has that name. Creation is the claim: two processes racing for
/// one name cannot both create it.
pub fn create_new(dir: &Path, now: SystemTime) -> Result<PathBuf, CampaignError> {
    std::fs::create_dir_all(dir).map_err(|source| ModelError::Io {
        path: dir.to_path_buf(),
        action: "cannot create",
        source,
    })?;
    let base = timestamped_folder(dir, now);
    for n in 1..=MAX_SUFFIX {
        let folder = if n == 1 {
            base.clone()
        } else {
            PathBuf::from(format!("{}-{n}", base.display()))
        };
        match std::fs::create_dir(&folder) {
            Ok(()) => return Ok(folder),
            Err(e) if e.kind() == ErrorKind::AlreadyExists => continue,
            Err(source) => {
                return Err(ModelError::Io {
                    path: folder,
                    action: "cannot create",
                    source,
                }
                .into());
            }
        }
    }
    Err(CampaignError::Config(format!(
        "{}: {MAX_SUFFIX} campaign folders already start with this name; use another --out",
        base.display()
    )))
}

/// `DIR/<YYYY-MM-DDTHH-MM-SS>` (UTC): ISO 8601 with `-` for `:` (which some file systems refuse), so the
/// folders sort by time.
pub fn timestamped_folder(dir: &Path, now: SystemTime) -> PathBuf {
    let secs = now.duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
    let (days, rem) = (secs / 86_400, secs % 86_400);
    let (year, month, day) = civil_from_days(days as i64);
    dir.join(format!(
        "{year:04}-{month:02}-{day:02}T{:02}-{:02}-{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    ))
}

/// Days since 1970-01-01 to (year, month, day) in the proleptic Gregorian calendar.
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

/// The advisory lock of one campaign folder, held until dropped (or the process ends). It is taken on the
/// folder itself, not on a file in it: deleting or replacing `campaign.lock` cannot let a second writer in.
/// The lock file only says which process writes (for the message of the one refused).
#[derive(Debug)]
pub struct FolderLock {
    _folder: File,
}

impl FolderLock {
    /// Takes `folder`'s lock, or says which process holds it.
    pub fn acquire(folder: &Path) -> Result<Self, CampaignError> {
        let io = |action: &'static str| {
            let path = folder.to_path_buf();
            move |source| ModelError::Io { path, action, source }
        };
        let handle = OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_DIRECTORY)
            .open(folder)
            .map_err(io("cannot open the campaign folder to lock it"))?;
        match try_lock_patiently(&handle) {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                // The pid is for the message only: an unreadable one still refuses.
                let holder = read_capped(&folder.join(LOCK_FILE), 64)
                    .map(|b| String::from_utf8_lossy(&b).trim().to_string())
                    .unwrap_or_default();
                let who = if holder.is_empty() || !holder.bytes().all(|b| b.is_ascii_digit()) {
                    "another process".to_string()
                } else {
                    format!("pid {holder}")
                };
                return Err(CampaignError::Config(format!(
                    "{}: this campaign is being written by {who}; one writer per campaign folder: wait for it \
                     to finish or stop it, then resume",
                    folder.display()
                )));
            }
            Err(TryLockError::Error(source)) => return Err(io("cannot lock")(source).into()),
        }
        // Replaced by rename: a link planted as the lock file is never written through.
        write_atomic(&folder.join(LOCK_FILE), format!("{}\n", std::process::id()).as_bytes())?;
        Ok(Self { _folder: handle })
    }
}

/// Polls the lock until it is free or [`LOCK_PATIENCE`] has passed.
fn try_lock_patiently(file: &File) -> Result<(), TryLockError> {
    let deadline = Instant::now() + LOCK_PATIENCE;
    loop {
        match file.try_lock() {
            Err(TryLockError::WouldBlock) if Instant::now() < deadline => std::thread::sleep(LOCK_POLL),
            other => return other,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::UNIX_EPOCH;

    #[test]
    fn folder_name_is_iso_8601_date_and_time() {
        // 2026-11-22 03:42:07 UTC
        let t = UNIX_EPOCH + Duration::from_secs(1_795_318_927);
        assert_eq!(
            timestamped_folder(Path::new("out"), t),
            PathBuf::from("out/2026-11-22T03-42-07")
        );
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(19_782), (2024, 2, 29));
    }

    #[test]
    fn campaigns_started_in_the_same_second_get_folders_of_their_own() {
        let dir = tempfile::tempdir().unwrap();
        let now = UNIX_EPOCH + Duration::from_secs(1_764_115_200);
        let a = create_new(dir.path(), now).unwrap();
        let b = create_new(dir.path(), now).unwrap();
        let c = create_new(dir.path(), now).unwrap();
        assert_ne!(a, b);
        assert_eq!(b, PathBuf::from(format!("{}-2", a.display())));
        assert_eq!(c, PathBuf::from(format!("{}-3", a.display())));
        assert!(a.is_dir() && b.is_dir() && c.is_dir());
    }

    #[test]
    fn a_held_folder_is_refused_naming_the_holder_and_freed_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let held = FolderLock::acquire(dir.path()).unwrap();
        let e = FolderLock::acquire(dir.path()).unwrap_err().to_string();
        assert!(e.contains(&format!("pid {}", std::process::id())), "{e}");
        assert!(e.contains("one writer per campaign folder"), "{e}");
        drop(held);
        FolderLock::acquire(dir.path()).unwrap();
    }

    #[test]
    fn a_deleted_or_linked_lock_file_lets_no_second_writer_in_and_harms_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let held = FolderLock::acquire(dir.path()).unwrap();
        std::fs::remove_file(dir.path().join(LOCK_FILE)).unwrap();
        let e = FolderLock::acquire(dir.path()).unwrap_err().to_string();
        assert!(e.contains("one writer per campaign folder"), "{e}");
        drop(held);
        let victim = dir.path().join("victim");
        std::fs::write(&victim, "precious").unwrap();
        std::os::unix::fs::symlink(&victim, dir.path().join(LOCK_FILE)).unwrap();
        let _lock = FolderLock::acquire(dir.path()).unwrap();
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    }

    #[test]
    fn a_lock_released_a_moment_later_is_taken_rather_than_refused() {
        let dir = tempfile::tempdir().unwrap();
        let held = FolderLock::acquire(dir.path()).unwrap();
        let releaser = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(200));
            drop(held);
        });
        FolderLock::acquire(dir.path()).unwrap();
        releaser.join().unwrap();
    }
}
