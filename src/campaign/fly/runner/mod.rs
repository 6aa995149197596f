//! Flights as jobs on an existing engine (`generate --runner 'COMMAND'`): each flight is a job folder with the
//! test and its files, a shell command run on it (Aerialist with its Docker or Kubernetes agent, `srun`, a
//! `kubectl` Job, ...), and what the job left read back and judged here. A failed job is retried once; a flight
//! whose retry fails too is journaled `backend_failed` (not charged to the budget) and the campaign goes on.

pub mod cancel;
pub mod job;
pub mod leftovers;
pub mod process;
pub mod readback;
pub mod template;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

use crate::campaign::fly::retry::{Attempt, Retry, Tried};
use crate::campaign::fly::vehicle::{Flown, Vehicle, VehicleError};
use crate::campaign::ground::flight_status::FlightStatus;
use crate::judge::Judge;
use crate::model::safe_files::{MAX_READ_BYTES, read_capped, read_tail};
use crate::model::{Spelling, TestCase, write_atomic};
use process::Ended;
pub use template::Template;

/// Default wall-time limit of one job, seconds: above Aerialist's own limit on a Docker test (its
/// `DOCKER_TIMEOUT`, 1000 s) plus a container's start.
pub const DEFAULT_JOB_TIMEOUT_S: f64 = 1200.0;
/// The command as run, kept in the job folder for a look or a rerun by hand (a job runs without it).
pub const COMMAND_FILE: &str = "prgenuav-job.sh";
/// Bytes of a failed job's stderr quoted in its reason.
const TAIL_BYTES: usize = 600;

/// What every runner of a campaign shares.
#[derive(Debug, Clone)]
pub struct RunnerSettings {
    /// The command template.
    pub template: Template,
    /// Wall-time limit of one job.
    pub timeout: Duration,
    /// The judge edition of the flights.
    pub judge: Judge,
    /// Key spelling of the job's test YAML.
    pub spelling: Spelling,
    /// The campaign folder; jobs go to its `jobs/`.
    pub campaign_folder: PathBuf,
    /// Cancels a stopped or timed-out job in its engine (`--runner-cancel`).
    pub cancel: Option<Template>,
}

/// One job slot: `--jobs N` of them run at most N jobs at once.
pub struct RunnerVehicle {
    index: usize,
    settings: Arc<RunnerSettings>,
    retry: Retry,
}

impl RunnerVehicle {
    /// Slot `index` (named `runner#index` in the journal).
    pub fn new(index: usize, settings: Arc<RunnerSettings>) -> Self {
        Self {
            index,
            settings,
            retry: Retry::default(),
        }
    }

    /// `jobs` slots sharing `settings`; `jobs` must be at least 1.
    pub fn fleet(settings: RunnerSettings, jobs: usize) -> Result<Vec<Box<dyn Vehicle>>, String> {
        if jobs == 0 {
            return Err("--jobs must be at least 1".into());
        }
        let shared = Arc::new(settings);
        Ok((0..jobs)
            .map(|i| Box::new(Self::new(i, shared.clone())) as Box<dyn Vehicle>)
            .collect())
    }

    /// One run of the job for `test` in `jobs/<candidate>`.
    fn attempt(&self, test: &TestCase, candidate: &str, attempt: usize, csv: &Path, cancel: &AtomicBool) -> Attempt {
        let s = &self.settings;
        let dir = s.campaign_folder.join("jobs").join(candidate);
        // A campaign killed outright left its job running: it is stopped before this flight starts again.
        if let Ok(absolute) = std::path::absolute(&dir) {
            leftovers::kill_marked(&absolute);
        }
        let folder = match job::prepare(&dir, test, s.spelling) {
            Ok(f) => f,
            Err(e) => return Attempt::Failed(format!("job folder: {e}")),
        };
        let id = job_id(&s.campaign_folder, candidate, attempt);
        let command = s
            .template
            .render(&folder.test.to_string_lossy(), &folder.dir.to_string_lossy(), &id);
        let mut skip = folder.inputs.clone();
        skip.push(folder.dir.join(COMMAND_FILE));
        let _ = write_atomic(&folder.dir.join(COMMAND_FILE), format!("{command}\n").as_bytes());
        let (stdout, stderr) = (folder.dir.join(job::STDOUT_FILE), folder.dir.join(job::STDERR_FILE));
        let ran = match process::run(&command, &folder.dir, &stdout, &stderr, s.timeout, cancel) {
            Ok(r) => r,
            Err(e) => return Attempt::Failed(format!("cannot start `sh -c {command}`: {e}")),
        };
        // A job the engine still holds is cancelled there too, when the template says how.
        let in_engine = || cancel::note(s.cancel.as_ref(), &folder.test, &folder.dir, &id);
        let code = match ran.ended {
            Ended::Cancelled => {
                let why = format!("the job was stopped{}", in_engine());
                return Attempt::Flew(Flown::unflown(FlightStatus::ABORTED, why));
            }
            Ended::TimedOut => {
                let limit = s.timeout.as_secs_f64();
                let (note, tail) = (in_engine(), tail(&stderr));
                return Attempt::Failed(format!(
                    "timed out after {limit:.0} s (--job-timeout), killed{note}{tail}"
                ));
            }
            Ended::Exited(code) => code,
        };
        // A stdout past the cap holds no report worth reading; the trajectory is looked for in files.
        let out = read_capped(&stdout, MAX_READ_BYTES).unwrap_or_default();
        let back = readback::read_back(&folder.dir, &skip, &out, &test.obstacles, s.judge);
        match (code, back) {
            // `fly` exits 1 when a flight did not complete, with its report: a result, not a failure.
            (Some(0), Ok(b)) | (_, Ok(b @ readback::Readback { reported: true, .. })) => {
                if let Some(t) = &b.trajectory
                    && let Err(e) = write_atomic(csv, t.to_csv().as_bytes())
                {
                    return Attempt::Failed(e.to_string());
                }
                Attempt::Flew(b.flown)
            }
            (Some(0), Err(e)) => Attempt::Failed(format!("{e}{}", tail(&stderr))),
            // A submitting command that failed (lost contact with its engine, say) may leave its job there:
            // cancelled before the retry, so one candidate never flies twice at once.
            (code, _) => failed_exit(code, &in_engine(), &stderr),
        }
    }
}

/// A job command that exited without a result: its exit in words, what was done about the job in its engine,
/// and the end of its error output.
fn failed_exit(code: Option<i32>, in_engine: &str, stderr: &Path) -> Attempt {
    let code = code.map_or("a signal".into(), |c| format!("code {c}"));
    Attempt::Failed(format!("exited with {code}{in_engine}{}", tail(stderr)))
}

impl Vehicle for RunnerVehicle {
    fn name(&self) -> String {
        format!("runner#{}", self.index)
    }

    fn fly(&mut self, test: &TestCase, csv: &Path, cancel: &AtomicBool) -> Result<Flown, VehicleError> {
        let candidate = csv
            .file_stem()
            .map_or_else(|| "candidate".into(), |s| s.to_string_lossy().into_owned());
        let mut retry = std::mem::take(&mut self.retry);
        let tried = retry.tries(cancel, |n| match self.attempt(test, &candidate, n, csv, cancel) {
            Attempt::Failed(why) => Attempt::Failed(format!("attempt {n}: {why}")),
            other => other,
        });
        self.retry = retry;
        match tried {
            Tried::Flew(f) => Ok(f),
            Tried::Stopped => Ok(stopped()),
            Tried::Failed(failures) => {
                let reason = format!("the job failed twice ({})", failures.join("; "));
                self.retry.failed(self.name(), reason)
            }
        }
    }
}

/// A flight the campaign's stop ended (`aborted`: the fleet journals it `interrupted`).
fn stopped() -> Flown {
    Flown::unflown(
        crate::campaign::ground::flight_status::FlightStatus::ABORTED,
        "the job was stopped".into(),
    )
}

/// `{id}`: unique per campaign, flight and attempt, and a valid Slurm job name and Kubernetes object name
/// (lowercase letters, digits, `-`): `prg-<campaign hash>-<candidate>-<attempt>`.
pub fn job_id(campaign_folder: &Path, candidate: &str, attempt: usize) -> String {
    // FNV-1a: stable across runs and platforms (the std hasher is not).
    let hash = campaign_folder
        .to_string_lossy()
        .bytes()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
        });
    // Every group of digits is kept, apart: `candidate_1_2` (a re-flight) and `candidate_12` differ.
    let groups: Vec<&str> = candidate
        .split(|c: char| !c.is_ascii_digit())
        .filter(|g| !g.is_empty())
        .collect();
    // Kubernetes names are at most 63 characters: the hash, the attempt and 40 digits fit.
    let number: String = groups.join("-").chars().take(40).collect();
    format!("prg-{:08x}-{number}-{attempt}", hash as u32)
}

/// The last lines of a job's stderr, for a failure's reason.
fn tail(stderr: &Path) -> String {
    let bytes = read_tail(stderr, TAIL_BYTES as u64).unwrap_or_default();
    let text = String::from_utf8_lossy(&bytes);
    let text = text.trim();
    if text.is_empty() {
        String::new()
    } else {
        format!("; stderr ends: {}", text.replace('\n', " | "))
    }
}

#[cfg(test)]
#[path = "runner_tests.rs"]
mod tests;
