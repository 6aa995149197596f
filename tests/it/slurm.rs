//! A campaign whose flights are Slurm jobs (`--runner 'srun ...'`) on a one-node cluster started here: munged,
//! slurmctld and slurmd from Debian's `slurm-wlm` and `munge`, configured in a temporary folder
//! (tests/data/slurm/slurm.conf.in), stopped at the end. Needs root and those packages, so it is ignored by
//! default; `.ci/run` installs them and runs it:
//! `cargo test --test it slurm -- --ignored --nocapture`.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use prgenuav::campaign::store::journal::Journal;

use super::repo;

/// The daemons started for one test, stopped (by their pid files) when dropped.
struct Cluster {
    dir: tempfile::TempDir,
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .expect("a free port")
}

fn run_ok(cmd: &mut Command) {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{cmd:?}: {e} (apt-get install -y slurm-wlm munge)"));
    assert!(
        out.status.success(),
        "{cmd:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

impl Cluster {
    fn start() -> Self {
        let dir = tempfile::tempdir().expect("temp dir");
        let d = dir.path();
        for sub in ["state", "spool", "munge"] {
            std::fs::create_dir_all(d.join(sub)).unwrap();
        }
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(d, std::fs::Permissions::from_mode(0o755)).unwrap();
        std::fs::set_permissions(d.join("munge"), std::fs::Permissions::from_mode(0o700)).unwrap();
        let key: Vec<u8> = (0..1024u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        std::fs::write(d.join("munge/munge.key"), key).unwrap();
        std::fs::set_permissions(d.join("munge/munge.key"), std::fs::Permissions::from_mode(0o600)).unwrap();
        let host = String::from_utf8(Command::new("hostname").output().unwrap().stdout).unwrap();
        let conf = std::fs::read_to_string(repo().join("tests/data/slurm/slurm.conf.in"))
            .unwrap()
            .replace("@DIR@", &d.display().to_string())
            .replace("@HOST@", host.trim())
            .replace(
                "@CPUS@",
                &std::thread::available_parallelism().map_or(1, |n| n.get()).to_string(),
            )
            .replace("@PORT1@", &free_port().to_string())
            .replace("@PORT@", &free_port().to_string());
        std::fs::write(d.join("slurm.conf"), conf).unwrap();
        let munge = |flag: &str, file: &str| format!("--{flag}={}", d.join("munge").join(file).display());
        run_ok(Command::new("munged").args([
            "--force".to_string(),
            munge("key-file", "munge.key"),
            munge("socket", "munge.sock"),
            munge("pid-file", "munged.pid"),
            munge("log-file", "munged.log"),
            munge("seed-file", "seed"),
        ]));
        let cluster = Self { dir };
        let conf = cluster.conf();
        run_ok(Command::new("slurmctld").arg("-f").arg(&conf));
        run_ok(Command::new("slurmd").arg("-f").arg(&conf).args(["-N", "localhost"]));
        cluster.wait_idle();
        cluster
    }

    fn conf(&self) -> PathBuf {
        self.dir.path().join("slurm.conf")
    }

    /// Until the node is idle, at most 30 s.
    fn wait_idle(&self) {
        let t0 = Instant::now();
        while t0.elapsed() < Duration::from_secs(30) {
            let out = Command::new("sinfo")
                .args(["-h", "-o", "%t"])
                .env("SLURM_CONF", self.conf())
                .output();
            if out.is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle") {
                return;
            }
            std::thread::sleep(Duration::from_millis(200));
        }
        let log = std::fs::read_to_string(self.dir.path().join("slurmctld.log")).unwrap_or_default();
        panic!("the Slurm node did not become idle in 30 s; slurmctld.log:\n{log}");
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for pid_file in ["slurmd.pid", "slurmctld.pid", "munge/munged.pid"] {
            let pid = std::fs::read_to_string(self.dir.path().join(pid_file)).unwrap_or_default();
            if let Ok(pid) = pid.trim().parse::<i32>() {
                // SAFETY: kill(2) on the daemon this test started.
                unsafe {
                    libc::kill(pid, libc::SIGTERM);
                }
            }
        }
        std::thread::sleep(Duration::from_millis(500));
    }
}

/// `mock-autopilot` beside the `prgenuav` under test, built if missing.
pub(super) fn mock_autopilot() -> PathBuf {
    let path = Path::new(env!("CARGO_BIN_EXE_prgenuav")).with_file_name("mock-autopilot");
    if !path.is_file() {
        run_ok(Command::new(env!("CARGO")).args(["build", "-p", "mock_autopilot", "--bin", "mock-autopilot"]));
    }
    path
}

/// A 4-flight campaign through `runner`; returns the campaign folder and each flight's wall time.
fn campaign(runner: &str, conf: &Path, out: &Path) -> (PathBuf, Vec<f64>) {
    campaign_on(&["--runner", runner, "--jobs", "2"], 4, "runner#", conf, out)
}

/// A static `flights`-flight campaign on `backend` (flags), each flight on a vehicle named `vehicle`...;
/// returns the campaign folder and each flight's wall time.
fn campaign_on(backend: &[&str], flights: usize, vehicle: &str, conf: &Path, out: &Path) -> (PathBuf, Vec<f64>) {
    let o = Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .args([
            "generate",
            "missions/mission2.yaml",
            &flights.to_string(),
            "--seed",
            "2",
        ])
        .args(backend)
        .args([
            "--no-learn",
            "--candidates",
            "12",
            "--ensemble",
            "0",
            "--confirm",
            "1",
            "--json",
            "--out",
        ])
        .arg(out)
        .env("SLURM_CONF", conf)
        .current_dir(repo())
        .output()
        .unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    let folder = PathBuf::from(v["output_folder"].as_str().unwrap());
    let records = Journal::read_all(&folder.join("journal.jsonl")).unwrap();
    assert_eq!(records.len(), flights, "{records:?}\n{stderr}");
    for r in &records {
        assert!(["landed", "collision"].contains(&r.flown.status.as_str()), "{r:?}");
        assert!(
            r.flown.min_distance.is_some() && r.vehicle.starts_with(vehicle),
            "{r:?}"
        );
    }
    (folder, records.iter().map(|r| r.wall_s).collect())
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    (v[(v.len() - 1) / 2] + v[v.len() / 2]) / 2.0
}

#[test]
#[ignore = "needs root, slurm-wlm and munge: cargo test --test it slurm -- --ignored"]
fn a_campaign_flies_its_tests_as_slurm_jobs() {
    let cluster = Cluster::start();
    let fly = repo().join("tests/data/slurm/fly-on-mock");
    let job = format!(
        "{} {} {} {{test}} {{dir}}",
        fly.display(),
        Path::new(env!("CARGO_BIN_EXE_prgenuav")).display(),
        mock_autopilot().display()
    );
    let out = tempfile::tempdir().unwrap();
    let srun = format!("srun -N1 -n1 --quiet -J {{id}} {job}");
    let (folder, through_slurm) = campaign(&srun, &cluster.conf(), out.path());
    let report = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(report.contains("| runner | 4 | 0 |"), "{report}");
    // The same flights without Slurm: the difference is Slurm's overhead per flight.
    let (_, direct) = campaign(&job, &cluster.conf(), out.path());
    let (s, d) = (median(through_slurm), median(direct));
    println!(
        "median wall time per flight: through srun {s:.3} s, direct {d:.3} s, overhead {:.3} s",
        s - d
    );
}

/// With `PX4_SITL_BIN` (a PX4 v1.14 `px4_sitl_default` build's `bin/px4`): 6 flights as `srun` steps of
/// `prgenuav fly --px4` (2 job slots on one node), then the same campaign with `--px4 --instances 2`; prints
/// Slurm's overhead per flight.
#[test]
#[ignore = "needs root, slurm-wlm, munge and PX4_SITL_BIN: cargo test --release --test it slurm -- --ignored"]
fn a_campaign_flies_px4_flights_as_slurm_jobs() {
    let build = super::px4_sitl_build().display().to_string();
    let cluster = Cluster::start();
    let out = tempfile::tempdir().unwrap();
    let srun = format!(
        "srun -N1 -n1 --quiet -J {{id}} {} fly {{test}} --px4 {build} --json --no-predict --trajectory {{dir}}/flight.csv",
        Path::new(env!("CARGO_BIN_EXE_prgenuav")).display()
    );
    let (_, through_slurm) = campaign_on(
        &["--runner", &srun, "--jobs", "2"],
        6,
        "runner#",
        &cluster.conf(),
        out.path(),
    );
    let (_, direct) = campaign_on(
        &["--px4", &build, "--instances", "2"],
        6,
        "px4-sih#",
        &cluster.conf(),
        out.path(),
    );
    let (s, d) = (median(through_slurm), median(direct));
    println!(
        "PX4: median wall time per flight through srun (fly --px4) {s:.3} s, --px4 {d:.3} s, overhead {:.3} s",
        s - d
    );
}

/// The names of the jobs Slurm holds now.
fn queued(conf: &Path) -> Vec<String> {
    let out = Command::new("squeue")
        .args(["-h", "-o", "%j"])
        .env("SLURM_CONF", conf)
        .output()
        .expect("squeue");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect()
}

/// `sbatch --wait` submits a job and waits for it: stopping that client leaves the job to Slurm, so a
/// stopped campaign must cancel it there (`--runner-cancel 'scancel --name {id}'`).
#[test]
#[ignore = "needs root, slurm-wlm and munge: cargo test --test it slurm -- --ignored"]
fn a_stopped_campaign_cancels_its_jobs_in_slurm() {
    let cluster = Cluster::start();
    let conf = cluster.conf();
    let out = tempfile::tempdir().unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .args([
            "generate",
            "missions/mission2.yaml",
            "4",
            "--no-learn",
            "--candidates",
            "8",
        ])
        .args(["--ensemble", "0", "--confirm", "1", "--quiet", "--jobs", "2"])
        .args([
            "--runner",
            "sbatch --wait --quiet -J {id} -o /dev/null --wrap 'sleep 300' # {test}",
        ])
        .args(["--runner-cancel", "scancel --name {id}", "--out"])
        .arg(out.path())
        .env("SLURM_CONF", &conf)
        .current_dir(repo())
        .stderr(std::fs::File::create(out.path().join("stderr.txt")).unwrap())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while !queued(&conf).iter().any(|j| j.starts_with("prg-")) {
        assert!(t0.elapsed() < Duration::from_secs(180), "no job reached Slurm");
        std::thread::sleep(Duration::from_millis(200));
    }
    let held = queued(&conf);
    run_ok(Command::new("kill").args(["-TERM", &child.id().to_string()]));
    let t1 = Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(t1.elapsed() < Duration::from_secs(30), "the campaign did not stop");
        std::thread::sleep(Duration::from_millis(100));
    }
    let stopped = t1.elapsed();
    // scancel returns before Slurm has ended the job: give it a few seconds.
    let t2 = Instant::now();
    let mut left = queued(&conf);
    while !left.is_empty() && t2.elapsed() < Duration::from_secs(15) {
        std::thread::sleep(Duration::from_millis(200));
        left = queued(&conf);
    }
    for name in &left {
        let _ = Command::new("scancel")
            .args(["--name", name])
            .env("SLURM_CONF", &conf)
            .status();
    }
    assert!(
        left.is_empty(),
        "held {held:?}; still in Slurm after the stop: {left:?}\n{}",
        campaign_trace(out.path())
    );
    println!(
        "{} job(s) cancelled in Slurm; the campaign stopped {:.1} s after SIGTERM, the queue was empty {:.1} s later",
        held.len(),
        stopped.as_secs_f64(),
        t2.elapsed().as_secs_f64()
    );
}

/// What a stopped campaign left to explain a failure: its error output, its journal and each job's cancel
/// output.
fn campaign_trace(folder: &Path) -> String {
    let read = |p: PathBuf| {
        format!(
            "--- {}\n{}",
            p.display(),
            std::fs::read_to_string(&p).unwrap_or_default()
        )
    };
    let mut parts = vec![read(folder.join("stderr.txt")), read(folder.join("journal.jsonl"))];
    if let Ok(jobs) = std::fs::read_dir(folder.join("jobs")) {
        for job in jobs.filter_map(Result::ok) {
            for file in [
                "prgenuav-cancel.stdout",
                "prgenuav-cancel.stderr",
                "prgenuav-job.stderr",
            ] {
                parts.push(read(job.path().join(file)));
            }
        }
    }
    parts.join("\n")
}
