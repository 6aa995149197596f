//! Runs one job's command (`sh -c`) in its folder, in a process group of its own, within a time limit: on
//! timeout or the campaign's stop the whole group is terminated, then killed, so nothing it started is left.

use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::leftovers::{MARKER, kill_marked};
use crate::model::safe_files::create_replacing;

/// After SIGTERM, the group has this long to stop before SIGKILL (srun forwards the signal to its step, and
/// `docker`/`kubectl` clients get to clean up).
pub const TERM_GRACE: Duration = Duration::from_secs(3);
/// The longest sleep between looks at the job (it starts at 1 ms and doubles): bounds how late a finished job,
/// a timeout or a stop is seen.
const MAX_POLL: Duration = Duration::from_millis(20);

/// How a job's process ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Ended {
    /// Exited with this code (`None`: killed by a signal it did not get from us).
    Exited(Option<i32>),
    /// Still running at the time limit: terminated.
    TimedOut,
    /// The campaign was stopped (Ctrl-C): terminated.
    Cancelled,
}

/// What one run of a job's command did.
#[derive(Debug, Clone)]
pub struct Ran {
    /// How it ended.
    pub ended: Ended,
    /// Wall time from start to end, seconds.
    pub wall_s: f64,
}

/// Runs `command` with `sh -c` in `dir`, stdin empty, stdout and stderr to `stdout`/`stderr` files, for at
/// most `timeout`; polls `cancel`. The process group is signalled at the end in every case, and every process
/// carrying the job's marker is killed, so background children the command left behind go too, detached or not.
pub fn run(
    command: &str,
    dir: &Path,
    stdout: &Path,
    stderr: &Path,
    timeout: Duration,
    cancel: &AtomicBool,
) -> std::io::Result<Ran> {
    let t0 = Instant::now();
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(command)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(create_replacing(stdout)?)
        .stderr(create_replacing(stderr)?)
        .env(MARKER, dir)
        .process_group(0)
        .spawn()?;
    let ended = watch(&mut child, t0 + timeout, cancel);
    if !matches!(ended, Ended::Exited(_)) {
        stop_group(&mut child);
    } else {
        // The leader is gone; whatever it left in its group is not the campaign's to keep.
        signal_group(&child, libc::SIGKILL);
    }
    // What left the group (`setsid`, a double fork) still carries the job's marker.
    kill_marked(dir);
    Ok(Ran {
        ended,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

/// Waits for `child` until it exits, `deadline` passes or `cancel` is set.
fn watch(child: &mut Child, deadline: Instant, cancel: &AtomicBool) -> Ended {
    let mut pause = Duration::from_millis(1);
    loop {
        match child.try_wait() {
            Ok(Some(status)) => return Ended::Exited(code(status)),
            Ok(None) => {}
            // Not waitable any more: treat as gone, with no code.
            Err(_) => return Ended::Exited(None),
        }
        if cancel.load(Ordering::Relaxed) {
            return Ended::Cancelled;
        }
        let now = Instant::now();
        if now >= deadline {
            return Ended::TimedOut;
        }
        std::thread::sleep(pause.min(deadline - now));
        pause = (pause * 2).min(MAX_POLL);
    }
}

fn code(status: ExitStatus) -> Option<i32> {
    status.code()
}

/// SIGTERM to the group, up to [`TERM_GRACE`] for the leader to exit, then SIGKILL to the group; reaps it.
fn stop_group(child: &mut Child) {
    signal_group(child, libc::SIGTERM);
    let deadline = Instant::now() + TERM_GRACE;
    while Instant::now() < deadline {
        if matches!(child.try_wait(), Ok(Some(_)) | Err(_)) {
            break;
        }
        std::thread::sleep(MAX_POLL);
    }
    signal_group(child, libc::SIGKILL);
    // After SIGKILL the leader exits at once; wait() cannot block for long.
    let _ = child.wait();
}

fn signal_group(child: &Child, signal: libc::c_int) {
    // The child leads its own group (process_group(0)), so its id is the group's id.
    let Ok(pgid) = libc::pid_t::try_from(child.id()) else {
        return;
    };
    // SAFETY: kill(2) with a negative pid signals that process group only; it touches no memory of ours.
    unsafe {
        libc::kill(-pgid, signal);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run_here(cmd: &str, timeout_ms: u64, cancel: &AtomicBool) -> (Ran, String, String) {
        let dir = tempfile::tempdir().unwrap();
        let (out, err) = (dir.path().join("o"), dir.path().join("e"));
        let ran = run(cmd, dir.path(), &out, &err, Duration::from_millis(timeout_ms), cancel).unwrap();
        (
            ran,
            std::fs::read_to_string(out).unwrap(),
            std::fs::read_to_string(err).unwrap(),
        )
    }

    #[test]
    fn exit_codes_and_output_are_kept() {
        let no = AtomicBool::new(false);
        let (ran, out, err) = run_here("pwd; echo oops >&2; exit 3", 5000, &no);
        assert_eq!(ran.ended, Ended::Exited(Some(3)));
        assert!(!out.trim().is_empty());
        assert_eq!(err, "oops\n");
    }

    #[test]
    fn a_hanging_job_and_its_children_are_killed_at_the_timeout() {
        let no = AtomicBool::new(false);
        let dir = tempfile::tempdir().unwrap();
        let pidfile = dir.path().join("pid");
        // A child that ignores SIGTERM, in the background: only the group's SIGKILL stops it.
        let cmd = format!(
            "sh -c 'trap \"\" TERM; echo $$ > {}; sleep 30' & sleep 30",
            pidfile.display()
        );
        let t0 = Instant::now();
        let (ran, _, _) = run_here(&cmd, 300, &no);
        assert_eq!(ran.ended, Ended::TimedOut);
        assert!(t0.elapsed() < Duration::from_secs(10), "{:?}", t0.elapsed());
        let pid: i32 = std::fs::read_to_string(&pidfile).unwrap().trim().parse().unwrap();
        std::thread::sleep(Duration::from_millis(100));
        // SAFETY: signal 0 only checks the process exists.
        let alive = unsafe { libc::kill(pid, 0) } == 0 && !zombie(pid);
        assert!(!alive, "the background child {pid} survived");
    }

    fn zombie(pid: i32) -> bool {
        std::fs::read_to_string(format!("/proc/{pid}/stat")).map_or(true, |s| s.contains(") Z "))
    }

    #[test]
    fn a_stop_ends_the_job() {
        let cancel = AtomicBool::new(true);
        let (ran, _, _) = run_here("sleep 30", 60_000, &cancel);
        assert_eq!(ran.ended, Ended::Cancelled);
        assert!(ran.wall_s < 10.0);
    }
}
