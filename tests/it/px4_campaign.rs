//! `--px4` against a real PX4 v1.14 SITL build (ignored by default, like [`super::px4_sitl`]):
//!
//! `PX4_SITL_BIN=/path/to/build/px4_sitl_default/bin/px4 cargo test --release -- --ignored px4_sitl
//! --nocapture --test-threads=1`
//!
//! The campaign's PX4 vehicle flies each flight on a fresh instance (instance 5 here, apart from the other
//! PX4 tests' 1-4), keeps its console and ULog, and leaves no process behind, even when prgenuav is killed.

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use prgenuav::bridge::sitl::Px4Build;
use prgenuav::campaign::fly::px4::{Px4Settings, Px4Vehicle};
use prgenuav::campaign::fly::vehicle::Vehicle;
use prgenuav::generator::{Generator, GeneratorConfig};

use super::campaign::{output_folder, spawn, verify_folder, wait_bounded};
use super::px4_fake::killed_parent_leaves_no_px4;
use super::{case, px4_sitl_build};

#[test]
#[ignore = "needs PX4_SITL_BIN (PX4 v1.14 SITL); run with --ignored px4_sitl"]
fn px4_sitl_vehicle_flies_each_flight_on_a_fresh_instance() {
    let build = px4_sitl_build();
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let settings = Px4Settings {
        keep_ulog: true,
        timeout_s: 400.0,
        ..Px4Settings::new(Px4Build::open(&build).expect("a PX4 build"), 5.0)
    };
    let mut v = Px4Vehicle::new(rt.handle().clone(), settings, 5);
    let c = case(2);
    let g = Generator::new(&c, GeneratorConfig::default(), 1).expect("generator");
    let out = tempfile::tempdir().unwrap();
    // Two flights in a row: the second must start at home on its own instance, as the first did.
    for k in 0..2 {
        let test = c.with_obstacles(g.sample(k).expect("sample").obstacles.to_vec());
        let csv = out.path().join(format!("flights/candidate_{k}.csv"));
        let wall = Instant::now();
        let f = v.fly(&test, &csv, &AtomicBool::new(false)).expect("flown");
        eprintln!(
            "px4_sitl: fresh instance flight {k} | {} | {:?} m | {:.0} s vehicle | {:.0} s wall | {:?}",
            f.status,
            f.min_distance,
            f.flight_time_s,
            wall.elapsed().as_secs_f64(),
            f.reason
        );
        let log = std::fs::read_to_string(csv.with_extension("px4.log")).expect("console kept");
        assert!(
            matches!(f.status.as_str(), "landed" | "collision"),
            "flight {k}: {} ({:?})\n{log}",
            f.status,
            f.reason
        );
        assert!(
            log.contains("=== attempt 1") && log.contains("Startup script returned"),
            "{log}"
        );
        let ulog = std::fs::metadata(csv.with_extension("ulg")).expect("--keep-ulog copy");
        assert!(
            ulog.len() > 10_000,
            "a ULog of a whole flight, not {} bytes",
            ulog.len()
        );
        let samples = std::fs::read_to_string(&csv).expect("trajectory");
        let first: Vec<f64> = samples
            .lines()
            .nth(1)
            .expect("a sample")
            .split(',')
            .filter_map(|x| x.parse().ok())
            .collect();
        assert!(first[1].hypot(first[2]) < 1.5, "flight {k} started at home: {first:?}");
    }
}

#[test]
#[ignore = "needs PX4_SITL_BIN (PX4 v1.14 SITL); run with --ignored px4_sitl"]
fn px4_sitl_a_killed_prgenuav_leaves_no_px4_behind() {
    let build = px4_sitl_build();
    // Killed once PX4 has booted and the flight is under way.
    killed_parent_leaves_no_px4(&build, Duration::from_secs(15), Some("px4"));
}

#[test]
#[ignore = "needs PX4_SITL_BIN (PX4 v1.14 SITL); run with --ignored px4_sitl"]
fn px4_sitl_a_campaign_killed_mid_flight_resumes_without_flying_twice() {
    let build = px4_sitl_build();
    let out = tempfile::tempdir().unwrap();
    let (build, dir) = (build.to_str().unwrap(), out.path().to_str().unwrap());
    let args = ["generate", "missions/mission2.yaml", "4", "--candidates", "12"];
    let mut child = spawn(&[&args[..], &["--px4", build, "--instances", "1", "--out", dir]].concat());
    // Killed with -9 once a flight is journaled, most likely with the next one in the air.
    let start = Instant::now();
    let folder = loop {
        let found = (std::fs::read_dir(out.path()).ok())
            .and_then(|mut d| d.next())
            .and_then(|e| e.ok())
            .map(|e| e.path());
        if let Some(f) = found.filter(|f| std::fs::read_to_string(f.join("journal.jsonl")).is_ok_and(|j| !j.is_empty()))
        {
            break f;
        }
        if start.elapsed() > Duration::from_secs(300) || child.try_wait().is_ok_and(|s| s.is_some()) {
            let _ = child.kill();
            panic!("no flight journaled on PX4 within 300 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    std::thread::sleep(Duration::from_secs(5));
    child.kill().expect("SIGKILL prgenuav");
    child.wait().expect("reap prgenuav");
    let resume = spawn(&["generate", "--resume", folder.to_str().unwrap()]);
    let (code, stdout, stderr) = wait_bounded(resume, Duration::from_secs(900));
    eprintln!("px4_sitl: resumed campaign\n{stderr}");
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("resuming"), "{stderr}");
    let report = verify_folder(&output_folder(&stdout));
    assert_eq!(report["suite"]["flown"], 4, "the budget is 4");
    let flights = report["flights"].as_array().unwrap();
    let mut ids: Vec<(u64, u64)> = (flights.iter())
        .map(|f| (f["candidate"].as_u64().unwrap(), f["attempt"].as_u64().unwrap_or(0)))
        .collect();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), flights.len(), "a flight was flown twice: {flights:?}");
}
