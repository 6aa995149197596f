//! Finding every process a job started, wherever it went: a job's processes carry its folder in their
//! environment ([`MARKER`]), which they inherit however they detach (a new process group, `setsid`, a double
//! fork). Killing by marker reaches what a process-group kill misses, and before a job is started again (a
//! resumed campaign) it stops whatever its earlier run left, so one flight never runs twice at once.

use std::path::Path;

/// The environment variable every job's processes inherit: the job folder's absolute path.
pub const MARKER: &str = "PRGENUAV_JOB_DIR";

/// Passes over the process table: a process may fork while the previous pass kills its parent.
const PASSES: usize = 8;
/// The most bytes of one process's environment looked at.
const MAX_ENVIRON_BYTES: u64 = 1 << 20;

/// Kills (SIGKILL) every process of this user whose environment marks it as a process of the job in `dir`,
/// and returns how many there were. Processes that are not ours cannot be read and are left alone.
pub fn kill_marked(dir: &Path) -> usize {
    let wanted = format!("{MARKER}={}", dir.display());
    let me = std::process::id();
    let mut killed = 0;
    for _ in 0..PASSES {
        let pids = marked(wanted.as_bytes(), me);
        if pids.is_empty() {
            break;
        }
        for pid in pids {
            // SAFETY: kill(2) on one process id; it touches no memory of ours.
            if unsafe { libc::kill(pid, libc::SIGKILL) } == 0 {
                killed += 1;
            }
        }
    }
    killed
}

/// The live processes (zombies aside) whose environment holds the entry `wanted`.
fn marked(wanted: &[u8], me: u32) -> Vec<libc::pid_t> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<u32>().ok())
        .filter(|&pid| pid != me)
        .filter(|&pid| !zombie(pid) && environ_holds(pid, wanted))
        .filter_map(|pid| libc::pid_t::try_from(pid).ok())
        .collect()
}

fn environ_holds(pid: u32, wanted: &[u8]) -> bool {
    use std::io::Read;
    let Ok(file) = std::fs::File::open(format!("/proc/{pid}/environ")) else {
        return false;
    };
    let mut bytes = Vec::new();
    if file.take(MAX_ENVIRON_BYTES).read_to_end(&mut bytes).is_err() {
        return false;
    }
    bytes.split(|b| *b == 0).any(|entry| entry == wanted)
}

fn zombie(pid: u32) -> bool {
    std::fs::read_to_string(format!("/proc/{pid}/stat")).map_or(true, |s| {
        s.rsplit_once(") ").is_some_and(|(_, rest)| rest.starts_with('Z'))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};

    #[test]
    fn a_setsid_grandchild_carrying_the_marker_is_found_and_killed() {
        let dir = tempfile::tempdir().unwrap();
        let pidfile = dir.path().join("pid");
        // The grandchild leaves the group and the session: only the marker still ties it to the job.
        let script = format!(
            "setsid sh -c 'echo $$ > {}; exec sleep 30' </dev/null >/dev/null 2>&1 &",
            pidfile.display()
        );
        let status = Command::new("sh")
            .arg("-c")
            .arg(&script)
            .env(MARKER, dir.path())
            .stdin(Stdio::null())
            .status()
            .unwrap();
        assert!(status.success());
        let t0 = Instant::now();
        while std::fs::read_to_string(&pidfile).map_or(true, |s| s.trim().is_empty()) {
            assert!(t0.elapsed() < Duration::from_secs(10), "the grandchild never started");
            std::thread::sleep(Duration::from_millis(20));
        }
        let pid: i32 = std::fs::read_to_string(&pidfile).unwrap().trim().parse().unwrap();
        assert!(kill_marked(dir.path()) >= 1);
        std::thread::sleep(Duration::from_millis(100));
        // SAFETY: signal 0 only checks the process exists.
        let alive = unsafe { libc::kill(pid, 0) } == 0 && !zombie(pid as u32);
        assert!(!alive, "the setsid grandchild {pid} survived");
        assert_eq!(kill_marked(dir.path()), 0, "nothing is left to kill");
    }
}
