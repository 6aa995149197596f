//! PX4's private working folders in the temp dir (`prgenuav-px4-<pid>-<instance>-<nanos>`): one per flight,
//! holding its parameters and its ULog (tens of MB), removed when the instance stops. A prgenuav killed with
//! SIGKILL cannot remove its own, so each new folder sweeps away those of processes that no longer run.

use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

const PREFIX: &str = "prgenuav-px4-";

/// A folder is swept only when untouched this long as well: a process in another PID namespace sharing the
/// temp dir is invisible here, and no flight keeps its folder unchanged for an hour.
pub const STALE_AFTER: Duration = Duration::from_secs(3600);

/// A fresh folder for `instance`, created; stale folders beside it are swept first.
pub fn create(instance: u8) -> std::io::Result<PathBuf> {
    let tmp = std::env::temp_dir();
    let nanos = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    let dir = tmp.join(format!("{PREFIX}{}-{instance}-{nanos}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    sweep_stale(&tmp, &dir, STALE_AFTER);
    Ok(dir)
}

/// The process id in a working folder's name; `None` for any other name.
fn owner(name: &str) -> Option<u32> {
    let mut parts = name.strip_prefix(PREFIX)?.split('-');
    let pid = parts.next()?.parse().ok()?;
    parts.next()?.parse::<u8>().ok()?;
    parts.next()?.parse::<u128>().ok()?;
    parts.next().is_none().then_some(pid)
}

/// Removes the working folders in `tmp` whose process is gone and which are older than `age`: only real
/// folders (never a link planted under such a name) of the user owning `mine`. Returns how many.
#[cfg(target_os = "linux")]
pub fn sweep_stale(tmp: &Path, mine: &Path, age: Duration) -> usize {
    use std::os::unix::fs::MetadataExt;
    let Ok(me) = std::fs::symlink_metadata(mine).map(|m| m.uid()) else {
        return 0;
    };
    let Ok(entries) = std::fs::read_dir(tmp) else { return 0 };
    let mut removed = 0;
    for entry in entries.flatten() {
        let Some(pid) = entry.file_name().to_str().and_then(owner) else {
            continue;
        };
        let Ok(meta) = entry.path().symlink_metadata() else {
            continue;
        };
        let old = meta
            .modified()
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|e| e >= age);
        let alive = Path::new("/proc").join(pid.to_string()).exists();
        if meta.is_dir() && meta.uid() == me && old && !alive && std::fs::remove_dir_all(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// Without `/proc` whether a process runs is not known here: nothing is swept.
#[cfg(not(target_os = "linux"))]
pub fn sweep_stale(_tmp: &Path, _mine: &Path, _age: Duration) -> usize {
    0
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    #[test]
    fn only_working_folder_names_have_an_owner() {
        assert_eq!(owner("prgenuav-px4-123-0-1795878383521940076"), Some(123));
        assert_eq!(owner("prgenuav-px4-slot-0.lock"), None);
        assert_eq!(owner("prgenuav-px4-123-0"), None);
        assert_eq!(owner("prgenuav-px4-123-0-5-6"), None);
        assert_eq!(owner("other-123-0-5"), None);
    }

    #[test]
    fn folders_of_ended_processes_go_and_live_ones_links_and_other_names_stay() {
        let tmp = tempfile::tempdir().expect("temp dir");
        let t = tmp.path();
        let mine = t.join(format!("{PREFIX}{}-0-1", std::process::id()));
        // Pid 4194304 is above Linux's pid_max limit: never a running process.
        let dead = t.join(format!("{PREFIX}4194304-1-2"));
        let kept = t.join("prgenuav-px4-slot-0.lock");
        let target = t.join("precious");
        for d in [&mine, &dead, &target] {
            std::fs::create_dir_all(d.join("log")).expect("folder");
        }
        std::fs::write(&kept, b"").expect("lock file");
        let link = t.join(format!("{PREFIX}4194305-1-3"));
        std::os::unix::fs::symlink(&target, &link).expect("link");

        assert_eq!(sweep_stale(t, &mine, STALE_AFTER), 0, "nothing is an hour old yet");
        assert_eq!(sweep_stale(t, &mine, Duration::ZERO), 1);
        assert!(!dead.exists());
        assert!(mine.exists() && kept.exists() && target.join("log").exists());
        assert!(link.symlink_metadata().is_ok(), "a planted link is left alone");
    }
}
