//! `--px4` without PX4: a fake `BUILD/bin/px4` (a shell script beside a `BUILD/etc`) that dies at boot or
//! never boots, to check the statuses, the retry on a fresh instance, the budget accounting and that no
//! process outlives prgenuav, even killed with SIGKILL. Runs in normal CI.

use prgenuav::campaign::ground::candidate::CandidateId;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use prgenuav::bridge::sitl::Px4Build;
use prgenuav::campaign::fly::fleet::fly_all;
use prgenuav::campaign::fly::px4::{Px4Settings, Px4Vehicle};
use prgenuav::campaign::fly::vehicle::{Job, Vehicle, VehicleError};
use prgenuav::campaign::ground::candidate::LfsPrediction;
use prgenuav::campaign::ground::flight_status::FlightStatus;
use prgenuav::campaign::store::journal::Journal;

use super::{case, repo, test_file, valid_pair};

/// A PX4 v1.14 build folder whose `bin/px4` runs `script` (PX4's arguments: `-d -i N -w DIR ETC`).
pub fn fake_build(script: &str) -> tempfile::TempDir {
    fake_build_tagged(script, "v1.14.0")
}

/// [`fake_build`] of the PX4 release whose git tag is `tag`.
pub fn fake_build_tagged(script: &str, tag: &str) -> tempfile::TempDir {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().expect("temp dir");
    let root = dir.path();
    std::fs::create_dir_all(root.join("bin")).expect("bin");
    std::fs::create_dir_all(root.join("etc/init.d-posix")).expect("etc");
    std::fs::write(root.join("etc/init.d-posix/rcS"), "").expect("rcS");
    let header = root.join(prgenuav::bridge::sitl::VERSION_HEADER);
    std::fs::create_dir_all(header.parent().expect("a folder")).expect("version folder");
    std::fs::write(header, format!("#define PX4_GIT_TAG_STR \"{tag}\"\n")).expect("version header");
    std::fs::write(root.join("bin/px4"), format!("#!/bin/sh\n{script}\n")).expect("px4");
    std::fs::set_permissions(root.join("bin/px4"), std::fs::Permissions::from_mode(0o755)).expect("chmod");
    dir
}

const DIES_AT_BOOT: &str = "echo 'ERROR [simulator_sih] fake px4: no sensors'\nexit 3";

/// Writes its pid (under its working folder's parent, the temp dir) and hangs without finishing its boot.
fn never_boots(pids: &Path) -> String {
    format!(
        "echo $$ >> '{}'\necho 'INFO  [init] fake px4 starting'\nexec sleep 120",
        pids.display()
    )
}

fn vehicle(build: &Path, boot: Duration) -> (tokio::runtime::Runtime, Px4Vehicle) {
    let rt = tokio::runtime::Runtime::new().expect("runtime");
    let settings = Px4Settings {
        boot_timeout: boot,
        ..Px4Settings::new(Px4Build::open(build).expect("a build"), 5.0)
    };
    let v = Px4Vehicle::new(rt.handle().clone(), settings, 7);
    (rt, v)
}

#[test]
fn a_px4_dying_at_boot_is_retried_once_then_journaled_backend_failed_and_the_vehicle_dropped() {
    let build = fake_build(DIES_AT_BOOT);
    let (_rt, mut v) = vehicle(build.path(), Duration::from_secs(10));
    let out = tempfile::tempdir().unwrap();
    let csv = out.path().join("flights/candidate_0.csv");
    let test = case(2).with_obstacles(valid_pair());
    let flown = v
        .fly(&test, &csv, &AtomicBool::new(false))
        .expect("journaled, not dropped");
    assert_eq!(flown.status, FlightStatus::BackendFailed);
    let reason = flown.reason.unwrap_or_default();
    assert!(
        reason.contains("two fresh instances")
            && reason.contains("exit status: 3")
            && reason.contains("no sensors")
            && reason.contains("flights/candidate_0.px4.log"),
        "{reason}"
    );
    let log = std::fs::read_to_string(out.path().join("flights/candidate_0.px4.log")).unwrap();
    assert!(log.contains("=== attempt 1") && log.contains("=== attempt 2"), "{log}");
    assert_eq!(log.matches("no sensors").count(), 2, "{log}");
    // The second flight in a row failing the same way drops the vehicle: its job goes back to the pool.
    let next = v.fly(
        &test,
        &out.path().join("flights/candidate_1.csv"),
        &AtomicBool::new(false),
    );
    assert!(
        matches!(&next, Err(VehicleError::Unreachable { reason, .. }) if reason.contains("2 flights in a row")),
        "{next:?}"
    );
}

#[test]
fn a_px4_that_never_boots_is_retried_on_a_fresh_instance_and_stopped_each_time() {
    let tmp = tempfile::tempdir().unwrap();
    let pids = tmp.path().join("pids");
    let build = fake_build(&never_boots(&pids));
    let (_rt, mut v) = vehicle(build.path(), Duration::from_secs(1));
    let csv = tmp.path().join("flights/candidate_3.csv");
    let t0 = Instant::now();
    let flown = v.fly(&case(2), &csv, &AtomicBool::new(false)).expect("journaled");
    assert_eq!(flown.status, FlightStatus::BackendFailed);
    let reason = flown.reason.unwrap_or_default();
    assert!(
        reason.contains("within 1 s") && reason.contains("fake px4 starting"),
        "{reason}"
    );
    assert!(t0.elapsed() < Duration::from_secs(20), "two bounded boots");
    let started: Vec<i32> = std::fs::read_to_string(&pids)
        .unwrap()
        .lines()
        .map(|l| l.trim().parse().unwrap())
        .collect();
    assert_eq!(started.len(), 2, "one fresh instance per attempt");
    for pid in started {
        assert!(gone(pid, Duration::from_secs(5)), "instance {pid} outlived its attempt");
    }
}

#[test]
fn backend_failures_are_journaled_but_not_charged_to_the_budget() {
    let build = fake_build(DIES_AT_BOOT);
    let (_rt, v) = vehicle(build.path(), Duration::from_secs(10));
    let folder = tempfile::tempdir().unwrap();
    let path = folder.path().join("journal.jsonl");
    let base = case(2).with_obstacles(valid_pair());
    let jobs: Vec<Job> = (0..3)
        .map(|i| {
            Job::new(
                CandidateId(i),
                Some(LfsPrediction::point(CandidateId(i), 1.0, 40.0, "landed".into())),
                base.clone(),
            )
        })
        .collect();
    let mut fleet: Vec<Box<dyn Vehicle>> = vec![Box::new(v)];
    let out = fly_all(
        &mut fleet,
        jobs,
        1,
        folder.path(),
        &mut Journal::load(&path).unwrap().0,
        &AtomicBool::new(false),
        &|_| {},
    );
    let all = Journal::read_all(&path).unwrap();
    let statuses: Vec<FlightStatus> = all.iter().map(|r| r.flown.status).collect();
    // Budget 1: the backend failure leaves it unspent, so the next job is tried, and drops the vehicle.
    assert_eq!(statuses, vec![FlightStatus::BackendFailed]);
    assert_eq!((out.flown, out.records.len()), (0, 0), "nothing charged");
    assert!(Journal::read(&path).unwrap().is_empty());
    assert_eq!((out.dropped.len(), fleet.len()), (1, 0), "{:?}", out.dropped);
}

#[test]
fn generate_with_a_dying_px4_journals_the_failure_and_stops_with_a_clear_error() {
    let build = fake_build(DIES_AT_BOOT);
    let out = tempfile::tempdir().unwrap();
    let (code, _, err) = super::prgenuav(&[
        "generate",
        "missions/mission2.yaml",
        "3",
        "--px4",
        build.path().to_str().unwrap(),
        "--instances",
        "1",
        "--no-screen",
        "--quiet",
        "--out",
        out.path().to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("no reachable vehicle") && err.contains("no sensors"),
        "{err}"
    );
    let folder = std::fs::read_dir(out.path()).unwrap().flatten().next().unwrap().path();
    let all = Journal::read_all(&folder.join("journal.jsonl")).unwrap();
    assert_eq!(all.len(), 1);
    // The lowest instance slot free on this machine (another PX4 may hold slot 0).
    assert_eq!(all[0].flown.status, FlightStatus::BackendFailed);
    assert!(all[0].vehicle.starts_with("px4-sih#"), "{}", all[0].vehicle);
    assert!(folder.join("flights/candidate_0.px4.log").is_file());
    let stored: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("campaign.json")).unwrap()).unwrap();
    assert_eq!(stored["vehicles"]["speed_factor"], 5.0);
}

#[test]
fn bad_px4_settings_are_refused_before_anything_runs() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    let build = fake_build(DIES_AT_BOOT);
    let b = build.path().to_str().unwrap();
    let repo_root = repo();
    let not_a_build = repo_root.to_str().unwrap();
    for (args, expected) in [
        (vec!["--px4", not_a_build], "bin/px4 is missing"),
        (vec!["--px4", b, "--instances", "0"], "--instances 0 is out of range"),
        (
            vec!["--px4", b, "--instances", "11"],
            "--instances 11 is out of range: 1 to 10",
        ),
        (vec!["--px4", b, "--speed-factor=0"], "--speed-factor 0"),
        (vec!["--instances", "2"], "need --px4"),
    ] {
        let mut argv = vec!["generate", "missions/mission2.yaml", "3", "--out", o];
        argv.extend(&args);
        let (code, _, err) = super::prgenuav(&argv);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(expected), "{args:?}: {err}");
    }
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0, "nothing written");
    let (_d, test) = test_file(2, valid_pair());
    let (code, _, err) = super::prgenuav(&["fly", test.to_str().unwrap(), "--px4", not_a_build]);
    assert!(code == 2 && err.contains("not a PX4 SITL build folder"), "{err}");
}

#[test]
fn a_killed_prgenuav_leaves_no_px4_behind() {
    let tmp = tempfile::tempdir().unwrap();
    let build = fake_build(&never_boots(&tmp.path().join("pids")));
    killed_parent_leaves_no_px4(build.path(), Duration::ZERO, None);
}

/// Starts `prgenuav fly --px4 build`, waits for its PX4 child (named `comm`, any if `None`) and `settle`
/// more, kills prgenuav with SIGKILL and checks the child is gone.
pub fn killed_parent_leaves_no_px4(build: &Path, settle: Duration, comm: Option<&str>) {
    let (_d, test) = test_file(2, valid_pair());
    let mut parent = Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .args([
            "fly",
            test.to_str().unwrap(),
            "--px4",
            build.to_str().unwrap(),
            "--quiet",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start prgenuav");
    let parent_pid = i32::try_from(parent.id()).unwrap();
    let t0 = Instant::now();
    let child = loop {
        if let Some(c) = children_of(parent_pid)
            .into_iter()
            .find(|(_, name)| comm.is_none_or(|c| c == name))
        {
            break c.0;
        }
        if t0.elapsed() > Duration::from_secs(30) {
            let _ = parent.kill();
            panic!("prgenuav started no px4 within 30 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    std::thread::sleep(settle);
    parent.kill().expect("SIGKILL prgenuav");
    parent.wait().expect("reap prgenuav");
    assert!(
        gone(child, Duration::from_secs(10)),
        "px4 {child} outlived its killed parent"
    );
}

/// (pid, command name) of every process whose parent is `pid`.
pub fn children_of(pid: i32) -> Vec<(i32, String)> {
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter_map(|e| {
            let child: i32 = e.file_name().to_str()?.parse().ok()?;
            let stat = std::fs::read_to_string(e.path().join("stat")).ok()?;
            let (name, rest) = stat.split_once(" (")?.1.rsplit_once(") ")?;
            let ppid: i32 = rest.split_whitespace().nth(1)?.parse().ok()?;
            (ppid == pid).then(|| (child, name.to_string()))
        })
        .collect()
}

/// Whether `pid` is gone (or a zombie waiting for a reaper that is not ours) within `wait`.
pub fn gone(pid: i32, wait: Duration) -> bool {
    let t0 = Instant::now();
    loop {
        let stat = PathBuf::from(format!("/proc/{pid}/stat"));
        match std::fs::read_to_string(&stat) {
            Err(_) => return true,
            Ok(s) if s.rsplit_once(") ").is_some_and(|(_, r)| r.starts_with('Z')) => return true,
            Ok(_) if t0.elapsed() > wait => return false,
            Ok(_) => std::thread::sleep(Duration::from_millis(50)),
        }
    }
}
