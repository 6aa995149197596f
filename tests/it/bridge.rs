//! The MAVLink bridge against the in-process mock autopilot on ephemeral ports: every mode on missions 1-3
//! with generated obstacles, a serial (pseudo-terminal) link, and faults. Every wait is bounded.

use std::sync::Arc;
use std::time::Duration;

use mavlink::dialects::common::MavMissionResult;
use mock_autopilot::{Faults, LinkSpec, MockAutopilot, MockHandle, SpeedFactor};
use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, Status, fly};
use prgenuav::generator::{Generator, GeneratorConfig};
use prgenuav::model::{Trajectory, TestCase};

use super::case;

/// Mock speed factor for the fast tests (the bridge's clock follows it).
const SPEED: f64 = 20.0;
/// No test may take longer than this (wall time).
const WALL_LIMIT: Duration = Duration::from_secs(60);

/// Mission `n` with generated obstacles (seed 1, test 0).
fn generated(n: u32) -> TestCase {
    let c = case(n);
    let g = Generator::new(&c, GeneratorConfig::default(), 1).expect("generator");
    c.with_obstacles(g.sample(0).expect("sample").obstacles.to_vec())
}

async fn mock(speed: f64, f: impl FnOnce(mock_autopilot::Builder) -> mock_autopilot::Builder) -> (MockHandle, String) {
    let b = MockAutopilot::builder()
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(SpeedFactor::Times(speed));
    let m = f(b).spawn().await.expect("mock starts");
    let port = m.local_addr().expect("udp").port();
    (m, format!("udpout:127.0.0.1:{port}"))
}

fn opts(url: &str, mode: FlyMode, speed: f64) -> FlyOptions {
    FlyOptions {
        connect: url.into(),
        mode,
        time_scale: speed,
        heartbeat_wait_s: 20.0,
        ..FlyOptions::default()
    }
}

async fn fly_bounded(test: &TestCase, o: &FlyOptions, cancel: CancelToken) -> FlightReport {
    tokio::time::timeout(WALL_LIMIT, fly(test, o, cancel))
        .await
        .expect("flight within the wall-time limit")
        .expect("flight runs")
}

fn assert_flown(r: &FlightReport, what: &str) {
    assert!(r.status.completed(), "{what}: {:?} {:?} {:?}", r.status, r.reason, r.warnings);
    assert!(r.samples > 100, "{what}: {} samples", r.samples);
    assert!(r.min_distance.is_some(), "{what}");
    assert!(r.flight_time_s > 5.0, "{what}: {} s", r.flight_time_s);
    assert!(r.link.packets_received > 100);
}

async fn fly_mode(mode: FlyMode, n: u32) -> FlightReport {
    let test = generated(n);
    let (m, url) = mock(SPEED, |b| b).await;
    let r = fly_bounded(&test, &opts(&url, mode, SPEED), CancelToken::new()).await;
    let state = m.state();
    assert!(!state.armed, "{mode:?} mission {n}: still armed");
    m.shutdown().await.expect("mock stops");
    eprintln!("{mode:?} mission {n}: {}", serde_json::to_string(&r).unwrap_or_default());
    assert_flown(&r, &format!("{mode:?} mission {n}"));
    // It flew the whole mission: it ended at the land point.
    let land = test.mission.flight_path().last().copied().expect("land item");
    let end = r.trajectory.samples.last().copied().expect("samples");
    let off = (end.x - land.north_m).hypot(end.y - land.east_m);
    assert!(off < 3.0, "{mode:?} mission {n}: landed {off:.1} m from the land point");
    if mode != FlyMode::Mission {
        assert_eq!(r.status, Status::Landed, "{mode:?} mission {n} avoids the boxes: {:?}", r.reason);
    }
    r
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mission_mode_missions_1_to_3() {
    for n in 1..=3 {
        let r = fly_mode(FlyMode::Mission, n).await;
        assert!(r.fence_uploaded, "the obstacles go up as a fence");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn avoidance_mode_missions_1_to_3() {
    for n in 1..=3 {
        fly_mode(FlyMode::Avoidance, n).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn offboard_mode_missions_1_to_3() {
    for n in 1..=3 {
        fly_mode(FlyMode::Offboard, n).await;
    }
}
