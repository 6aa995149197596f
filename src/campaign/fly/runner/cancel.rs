//! `--runner-cancel 'COMMAND'`: a job handed to an engine (a Slurm allocation, a Kubernetes Job) may outlive
//! the local command that submitted it, so stopping that command is not enough. When a job is stopped (the
//! campaign's Ctrl-C, SIGTERM or SIGHUP) or runs past its time limit, this command, with the job's `{id}`,
//! asks the engine to cancel it: once, within a time limit, its output kept in the job folder.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use super::process::{self, Ended};
use super::template::Template;

/// Wall-time limit of one cancel command: with the job's own stop ([`process::TERM_GRACE`]) it stays well
/// within the 20 s a stopped campaign takes at most.
pub const CANCEL_TIMEOUT: Duration = Duration::from_secs(10);
/// Where the cancel command's output goes, in the job folder.
pub const CANCEL_STDOUT: &str = "prgenuav-cancel.stdout";
/// Its error output, beside it.
pub const CANCEL_STDERR: &str = "prgenuav-cancel.stderr";

/// `; ` and what [`cancel_job`] did, or nothing without a cancel command.
pub fn note(template: Option<&Template>, test: &Path, dir: &Path, id: &str) -> String {
    template.map_or_else(String::new, |t| format!("; {}", cancel_job(t, test, dir, id)))
}

/// Runs `template` for the job `id` flying `test` in `dir`; what it did, in words, for the flight's reason.
pub fn cancel_job(template: &Template, test: &Path, dir: &Path, id: &str) -> String {
    let command = template.render(&test.to_string_lossy(), &dir.to_string_lossy(), id);
    let (stdout, stderr) = (dir.join(CANCEL_STDOUT), dir.join(CANCEL_STDERR));
    // Its own flag: the campaign's is already set, and the cancel must still run.
    let never = AtomicBool::new(false);
    match process::run(&command, dir, &stdout, &stderr, CANCEL_TIMEOUT, &never) {
        Err(e) => format!("cannot start `{command}`: {e}"),
        Ok(ran) => match ran.ended {
            Ended::Exited(Some(0)) => format!("`{command}` asked the engine to cancel it"),
            Ended::Exited(code) => format!(
                "`{command}` failed ({}; {CANCEL_STDERR} in the job folder)",
                code.map_or("killed by a signal".into(), |c| format!("exit code {c}"))
            ),
            Ended::TimedOut | Ended::Cancelled => format!(
                "`{command}` did not end within {} s and was killed",
                CANCEL_TIMEOUT.as_secs()
            ),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cancel_command_gets_the_id_and_its_outcome_is_told() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let t = Template::parse_cancel("echo cancel {id} > cancelled").unwrap();
        let said = cancel_job(&t, &d.join("test.yaml"), d, "prg-1-2-1");
        assert!(said.contains("asked the engine"), "{said}");
        assert_eq!(
            std::fs::read_to_string(d.join("cancelled")).unwrap(),
            "cancel prg-1-2-1\n"
        );
        let t = Template::parse_cancel("echo no such job {id} >&2; exit 3").unwrap();
        let said = cancel_job(&t, &d.join("test.yaml"), d, "prg-1-2-1");
        assert!(said.contains("exit code 3") && said.contains(CANCEL_STDERR), "{said}");
        assert!(
            std::fs::read_to_string(d.join(CANCEL_STDERR))
                .unwrap()
                .contains("no such job")
        );
    }
}
