//! Conformance of real PX4 SITL flown by prgenuav's iris simulator, in external-simulator mode and lockstep
//! (ignored by default; CI does not run it). Needs PX4 SITL builds the user made:
//!
//! `PX4_SITL_BIN=/path/to/v1.14/build/px4_sitl_default/bin/px4 cargo test --release --test it px4_iris --
//! --ignored --nocapture --test-threads=1` (`PX4_SITL_BIN_V116` and `PX4_SITL_BIN_V112` fly the same on a
//! v1.16.x and a v1.12.x build).
//!
//! Missions 1-3 in every mode: the release's modes land and are judged exactly as the trajectory recomputes,
//! with no pre-flight, failsafe or timeout message from PX4 (beyond mission mode's geofence breach), at most one
//! lockstep wait in 5 000 timed out and no hold of simulated time released late; a mode the release lacks is refused before anything is armed. One line per
//! flight goes to stderr (docs/simulator.md's conformance table is made from them).

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use prgenuav::bridge::hil::sitl::{IrisSitl, IrisSpec};
use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, SimLink, fly};
use prgenuav::judge::judge_in_frame;
use prgenuav::model::TestCase;

use super::px4_release::release_bin;
use super::px4_sitl::{assert_landed_at_the_land_point, assert_refused_before_arming, build_of, generated};
use super::px4_sitl_bin;

/// The lockstep cap (PX4_SIM_SPEED_FACTOR) of every pair.
const SPEED: f64 = 5.0;
/// At most one lockstep step in this many may go on without PX4's answer.
const MAX_TIMEOUT_SHARE: u64 = 5_000;
/// PX4 messages no SIH flight of the same test gives.
const UNWANTED: [&str; 5] = ["Preflight Fail", "Failsafe", "timeout", "not ready", "no RC"];

/// Flies `test` in `mode` on a fresh PX4 + simulator pair (instance `instance`, simulator seed 0).
fn fly_iris(rt: &tokio::runtime::Runtime, bin: &Path, instance: u8, test: &TestCase, mode: FlyMode, what: &str) {
    let build = build_of(bin);
    let spec = IrisSpec {
        build: build.clone(),
        instance,
        home: test.home,
        heading_deg: 0.0,
        seed: 0,
        speed_factor: SPEED,
        link: SimLink::Tcp,
        paced: mode == FlyMode::Avoidance,
        boot_timeout: Duration::from_secs(60),
    };
    let stop = AtomicBool::new(false);
    let mut pair = IrisSitl::start(rt.handle(), &spec, &stop).unwrap_or_else(|e| panic!("{what}: {e}"));
    let opts = FlyOptions {
        connect: pair.px4.url(),
        mode,
        time_scale: SPEED,
        timeout_s: 400.0,
        heartbeat_wait_s: 60.0,
        lockstep: Some(Duration::ZERO),
        detect_time_scale: true,
        sim_gate: pair.gate(),
        ..FlyOptions::default()
    };
    let wall = Instant::now();
    let r = rt
        .block_on(async { tokio::time::timeout(Duration::from_secs(300), fly(test, &opts, CancelToken::new())).await })
        .unwrap_or_else(|_| panic!("{what}: flight within 5 min of wall time"))
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let summary = pair
        .finish()
        .unwrap_or_else(|| panic!("{what}: the simulator's account"));
    eprintln!(
        "px4_iris: {what} {mode:?} | {} | {} m | {:.0} s vehicle | {:.1} s wall | {summary} | {:?}",
        r.status.as_str(),
        r.min_distance.map_or("-".into(), |d| format!("{d:.3}")),
        r.flight_time_s,
        wall.elapsed().as_secs_f64(),
        r.warnings
    );
    if !build.release.supports(mode) {
        assert_refused_before_arming(&r, &format!("{what} {mode:?}"));
        return;
    }
    assert_landed_at_the_land_point(&pair.px4, &r, test, mode, &format!("{what} {mode:?}"));
    assert_judged_as_recomputed(&r, test, what);
    // Mission mode flies into the first box, whose geofence PX4 then reports as SIH does.
    let unwanted: Vec<&str> = r
        .vehicle_messages
        .iter()
        .map(|m| m.text.as_str())
        .filter(|t| mode != FlyMode::Mission && UNWANTED.iter().any(|u| t.contains(u)))
        .collect();
    assert!(unwanted.is_empty(), "{what} {mode:?}: PX4 said {unwanted:?}");
    // A lockstep step taken without PX4's answer (100 ms of wall time) is rare but not nil: v1.12.3 misses
    // 1-2 answers a flight (of 14 000-21 000 steps), v1.14 and v1.16.2 none.
    assert!(
        summary.actuator_timeouts * MAX_TIMEOUT_SHARE <= summary.steps && summary.late_releases == 0,
        "{what} {mode:?}: {summary}"
    );
    assert_eq!(summary.error, None, "{what} {mode:?}");
}

/// The reported distance is the judge's on the reported trajectory, to the bit.
fn assert_judged_as_recomputed(r: &FlightReport, test: &TestCase, what: &str) {
    let again = judge_in_frame(&r.trajectory, &test.obstacles, r.judge).map(|d| d.min_distance);
    assert_eq!(again, r.min_distance, "{what}: judged again from its trajectory");
}

/// Missions `mission` in every mode, each on a fresh pair.
fn all_modes(bin: &Path, instance: u8, mission: u32) {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    let test = generated(mission, 0);
    let what = format!("PX4 {} iris mission {mission}", build_of(bin).version);
    for mode in [FlyMode::Mission, FlyMode::Avoidance, FlyMode::Offboard] {
        fly_iris(&rt, bin, instance, &test, mode, &what);
    }
}

#[test]
#[ignore = "needs PX4_SITL_BIN (PX4 SITL); run with --ignored px4_iris"]
fn px4_iris_missions_1_to_3() {
    for mission in 1..=3 {
        all_modes(&px4_sitl_bin(), 1, mission);
    }
}

#[test]
#[ignore = "needs PX4_SITL_BIN_V116 (PX4 v1.16 SITL); run with --ignored px4_iris"]
fn px4_iris_v116_missions_1_to_3() {
    for mission in 1..=3 {
        all_modes(&release_bin("PX4_SITL_BIN_V116", 16), 2, mission);
    }
}

#[test]
#[ignore = "needs PX4_SITL_BIN_V112 (PX4 v1.12 SITL); run with --ignored px4_iris"]
fn px4_iris_v112_missions_1_to_3() {
    for mission in 1..=3 {
        all_modes(&release_bin("PX4_SITL_BIN_V112", 12), 3, mission);
    }
}
