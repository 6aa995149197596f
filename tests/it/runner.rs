//! `generate --runner`: campaigns whose flights are jobs, through the Aerialist stand-in (its output layout,
//! a ULog recorded from a mock flight) and through commands that fail.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use prgenuav::bridge::FlyMode;
use prgenuav::campaign::fly::mock_mavlink::MockVehicle;
use prgenuav::campaign::fly::vehicle::Vehicle;
use prgenuav::campaign::ground::flight_status::FlightStatus;
use prgenuav::campaign::store::journal::Journal;
use prgenuav::model::{Trajectory, load_ulog_trajectory};

use super::ulog::ULogWriter;
use super::{case, prgenuav, repo};

/// The stand-in for `aerialist` (tests/data/aerialist-standin/README.md).
fn standin() -> PathBuf {
    repo().join("tests/data/aerialist-standin/aerialist")
}

/// The stand-in's ULog: mission 2 flown on the embedded mock (avoidance, lockstep), its trajectory written as
/// PX4's `vehicle_local_position` (NED, z down, from 20 s after boot). Regenerate with
/// `cargo test --test it record_the_standin_ulog -- --ignored`.
#[test]
#[ignore = "writes tests/data/aerialist-standin/flight.ulg"]
fn record_the_standin_ulog() {
    let runtime = tokio::runtime::Runtime::new().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("flight.csv");
    let test = case(2).with_obstacles(super::valid_pair());
    let mut mock = MockVehicle::new(
        runtime.handle().clone(),
        0,
        20.0,
        FlyMode::Avoidance,
        Some(std::time::Duration::ZERO),
    );
    let flown = mock.fly(&test, &csv, &AtomicBool::new(false)).unwrap();
    assert_eq!(flown.status, FlightStatus::LANDED, "{flown:?}");
    let t = Trajectory::load_csv(&csv).unwrap();
    let mut w = ULogWriter::new().local_position_format();
    for s in &t.samples {
        let t_us = 20_000_000 + (s.t_s * 1e6).round() as u64;
        w = w.sample(t_us, s.x as f32, s.y as f32, -s.z as f32, s.r.unwrap_or(0.0) as f32);
    }
    std::fs::write(repo().join("tests/data/aerialist-standin/flight.ulg"), w.finish()).unwrap();
}

fn output_folder(stdout: &str) -> PathBuf {
    let v: serde_json::Value = serde_json::from_str(stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    PathBuf::from(v["output_folder"].as_str().unwrap())
}

fn files_named(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(files_named(&p, ext));
        } else if p.extension().is_some_and(|x| x == ext) {
            out.push(p);
        }
    }
    out
}

#[test]
fn a_campaign_flies_through_aerialist_with_the_docker_agent() {
    let out = tempfile::tempdir().unwrap();
    let runner = format!("{} exec --test {{test}} --agent docker", standin().display());
    let (code, stdout, stderr) = prgenuav(&[
        "generate",
        "missions/mission2.yaml",
        "3",
        "--seed",
        "4",
        "--runner",
        &runner,
        "--jobs",
        "2",
        "--out",
        out.path().to_str().unwrap(),
        "--json",
        "--no-learn",
        "--candidates",
        "8",
        "--ensemble",
        "0",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let folder = output_folder(&stdout);
    let records = Journal::read_all(&folder.join("journal.jsonl")).unwrap();
    assert_eq!(records.len(), 3, "{records:?}");
    let recorded = load_ulog_trajectory(&repo().join("tests/data/aerialist-standin/flight.ulg")).unwrap();
    for r in &records {
        assert!(r.vehicle.starts_with("runner#"), "{}", r.vehicle);
        assert!(["landed", "collision"].contains(&r.flown.status.as_str()), "{r:?}");
        assert!(r.flown.min_distance.is_some());
        // The judged trajectory is the recorded flight's, origin-aligned, in the campaign's CSV.
        let t = Trajectory::load_csv(&folder.join(&r.trajectory)).unwrap();
        assert_eq!(t.samples.len(), recorded.samples.len());
        // Aerialist's layout in the job folder: results/logs/<id>/<id>_<container>.ulg.
        let job = folder.join("jobs").join(format!("candidate_{}", r.candidate));
        let logs = files_named(&job.join("results/logs"), "ulg");
        assert_eq!(logs.len(), 1, "{logs:?}");
        assert!(job.join("logs/root.txt").is_file());
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("report.json")).unwrap()).unwrap();
    let backends = report["backends"].as_array().unwrap();
    assert_eq!(backends.len(), 1, "{backends:?}");
    assert_eq!(backends[0]["backend"], "runner");
    assert_eq!(backends[0]["flights"], 3);
    assert_eq!(backends[0]["failed_jobs"], 0);
    let md = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(md.contains("| runner | 3 | 0 |"), "{md}");
}

#[test]
fn the_kubernetes_agent_needs_a_path_and_leaves_its_logs_in_tmp() {
    let out = tempfile::tempdir().unwrap();
    let bare = format!("{} exec --test {{test}} --agent k8s", standin().display());
    let with_path = format!("{bare} --path {{dir}}/cloud --id {{id}}");
    let run = |runner: &str| {
        prgenuav(&[
            "generate",
            "missions/mission2.yaml",
            "1",
            "--runner",
            runner,
            "--out",
            out.path().to_str().unwrap(),
            "--json",
            "--no-learn",
            "--job-timeout",
            "60",
            "--candidates",
            "4",
            "--ensemble",
            "0",
        ])
    };
    let (code, stdout, stderr) = run(&with_path);
    assert_eq!(code, 0, "{stderr}");
    let folder = output_folder(&stdout);
    let r = &Journal::read(&folder.join("journal.jsonl")).unwrap()[0];
    let job = folder.join("jobs").join(format!("candidate_{}", r.candidate));
    assert_eq!(files_named(&job.join("tmp"), "ulg").len(), 1);
    // Without --path Aerialist's k8s agent fails: twice, then the flight is backend_failed, not charged.
    let (_, stdout, _) = run(&bare);
    let folder = output_folder(&stdout);
    let all = Journal::read_all(&folder.join("journal.jsonl")).unwrap();
    assert_eq!(all[0].flown.status, FlightStatus::BackendFailed, "{all:?}");
    let reason = all[0].flown.reason.as_deref().unwrap();
    assert!(
        reason.contains("exited with code 1") && reason.contains("endswith"),
        "{reason}"
    );
}

#[test]
fn a_broken_runner_is_dropped_after_two_failed_flights_and_nothing_is_charged() {
    let out = tempfile::tempdir().unwrap();
    let (code, stdout, stderr) = prgenuav(&[
        "generate",
        "missions/mission2.yaml",
        "2",
        "--runner",
        "echo cannot reach the cluster >&2; exit 3; : {test}",
        "--out",
        out.path().to_str().unwrap(),
        "--quiet",
        "--no-learn",
        "--candidates",
        "6",
        "--ensemble",
        "0",
    ]);
    // The second flight in a row that fails on the backend drops the runner (fly/retry.rs): with no vehicle
    // left the campaign says why and how to resume, and exits 1 with a report, as a budget of 1 whose one
    // flight failed on its backend does.
    assert_eq!(code, 1, "no vehicle left: {stdout}{stderr}");
    assert!(
        stderr.contains("2 flights in a row failed on the backend") && stderr.contains("cannot reach the cluster"),
        "{stderr}"
    );
    assert!(stderr.contains("--resume"), "{stderr}");
    let folder = std::fs::read_dir(out.path()).unwrap().next().unwrap().unwrap().path();
    let report = std::fs::read_to_string(folder.join("report.md")).expect("report.md");
    assert!(
        report.contains("cannot reach the cluster"),
        "the backend failure in report.md: {report}"
    );
    let all = Journal::read_all(&folder.join("journal.jsonl")).unwrap();
    assert!(
        all.len() == 1 && all[0].flown.status == FlightStatus::BackendFailed,
        "the first failed flight is journaled, the second given back with the runner: {all:?}"
    );
    assert!(
        all[0]
            .flown
            .reason
            .as_deref()
            .unwrap()
            .contains("cannot reach the cluster"),
        "{all:?}"
    );
    assert!(
        Journal::read(&folder.join("journal.jsonl")).unwrap().is_empty(),
        "none charged"
    );
}

#[test]
fn bad_runner_settings_are_refused_before_anything_runs() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    for (extra, says) in [
        (vec!["--runner", "aerialist exec --agent docker"], "no {test}"),
        (
            vec!["--runner", "fly {test} --out {output}"],
            "unknown placeholder {output}",
        ),
        (
            vec!["--runner", "fly {test}", "--jobs", "0"],
            "--jobs 0 is out of range: 1 to 1024",
        ),
        (vec!["--runner", "fly {test}", "--job-timeout=-1"], "--job-timeout"),
        (vec!["--job-timeout", "5"], "go with --runner"),
        (vec!["--jobs", "2", "--mock-vehicles", "3"], "disagree"),
        (
            vec!["--jobs", "2", "--connect", "udpin:0.0.0.0:14540"],
            "each URL flies one flight",
        ),
        (
            vec!["--runner", "fly {test}", "--connect", "udpin:0.0.0.0:14540"],
            "cannot be used with",
        ),
    ] {
        let mut args = vec!["generate", "missions/mission2.yaml", "2", "--out", o];
        args.extend(extra);
        let (code, _, stderr) = prgenuav(&args);
        assert_eq!(code, 2, "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0, "nothing written");
}

/// A Collision Prevention campaign whose flights are `prgenuav fly --json` jobs (on a mock autopilot): each
/// flight's verdict (closest centre, inside `CP_DIST`) is journaled as the embedded backends journal it,
/// measured on the trajectory the job left.
#[test]
fn a_runner_campaign_journals_each_collision_prevention_verdict() {
    let out = tempfile::tempdir().unwrap();
    let job = format!(
        "{} {} {} {{test}} {{dir}} --mode collision-prevention",
        repo().join("tests/data/slurm/fly-on-mock").display(),
        Path::new(env!("CARGO_BIN_EXE_prgenuav")).display(),
        super::slurm::mock_autopilot().display()
    );
    let (code, stdout, stderr) = prgenuav(&[
        "generate",
        "missions/mission2.yaml",
        "1",
        "--mode",
        "collision-prevention",
        "--seed",
        "0",
        "--runner",
        &job,
        "--job-timeout",
        "300",
        "--out",
        out.path().to_str().unwrap(),
        "--json",
        "--no-learn",
        "--candidates",
        "6",
        "--ensemble",
        "0",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let folder = output_folder(&stdout);
    let records = Journal::read_all(&folder.join("journal.jsonl")).unwrap();
    assert!(!records.is_empty(), "nothing flown: {stderr}");
    for r in &records {
        assert!(r.vehicle.starts_with("runner#"), "{r:?}");
        let job = folder.join("jobs").join(format!("candidate_{}", r.candidate));
        let said = std::fs::read_to_string(job.join("prgenuav-job.stdout")).unwrap();
        let said: serde_json::Value = serde_json::from_str(&said).unwrap_or_else(|e| panic!("{e}: {said}"));
        let cp = &said["collision_prevention"];
        let cp_dist = cp["cp_dist_m"]
            .as_f64()
            .unwrap_or_else(|| panic!("the job's CP verdict: {said}"));
        let centre = r
            .flown
            .closest_centre_m
            .unwrap_or_else(|| panic!("closest centre journaled: {r:?}"));
        assert_eq!(r.flown.inside_cp_dist, Some(centre < cp_dist), "{r:?}");
        // Measured again here on the trajectory the job left: what the job itself measured, within the
        // origin alignment both distances are judged in.
        let theirs = cp["closest_centre_m"].as_f64().unwrap();
        assert!(
            (centre - theirs).abs() < 0.1,
            "journaled {centre}, the job said {theirs}"
        );
    }
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("report.json")).unwrap()).unwrap();
    let flights: u64 = report["collision_prevention"]
        .as_array()
        .expect("a CP verdict per test")
        .iter()
        .map(|t| t["flights"].as_u64().unwrap())
        .sum();
    assert_eq!(flights as usize, records.len());
}
