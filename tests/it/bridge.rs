//! The MAVLink bridge against the in-process mock autopilot on ephemeral ports: every mode on missions 1-3
//! with generated obstacles, a serial (pseudo-terminal) link, and faults. Every wait is bounded.

use std::time::Duration;

use mavlink::dialects::common::MavMissionResult;
use mock_autopilot::{Faults, LinkSpec, MockAutopilot, MockHandle, SpeedFactor};
use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, Status, fly};
use prgenuav::generator::{Generator, GeneratorConfig};
use prgenuav::model::{TestCase, Trajectory};

use super::case;

/// Mock speed factor for the fast tests (the bridge's clock follows it).
const SPEED: f64 = 20.0;
/// Speed factor when the planner steers: 10 Hz of vehicle time is 100 plans per wall second, which leaves a
/// loaded 2-core CI machine headroom (a stale plan is mirrored, and the drone would fly straight).
const PLANNED_SPEED: f64 = 10.0;
/// Upper bound of a lockstep mock's clock: the mock waits for every avoidance answer, however slow the build.
const LOCKSTEP_SPEED: f64 = 100.0;
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
    assert!(
        r.status.completed(),
        "{what}: {:?} {:?} {:?}",
        r.status,
        r.reason,
        r.warnings
    );
    assert!(r.samples > 100, "{what}: {} samples", r.samples);
    assert!(r.min_distance.is_some(), "{what}");
    assert!(r.flight_time_s > 5.0, "{what}: {} s", r.flight_time_s);
    assert!(r.link.packets_received > 100);
}

async fn fly_mode(mode: FlyMode, n: u32) -> FlightReport {
    let test = generated(n);
    // Avoidance flies in lockstep (the free-running companion is covered by the serial and fault tests).
    let lockstep = (mode == FlyMode::Avoidance).then_some(Duration::ZERO);
    let speed = match mode {
        FlyMode::Mission => SPEED,
        FlyMode::Avoidance => LOCKSTEP_SPEED,
        FlyMode::Offboard | FlyMode::CollisionPrevention => PLANNED_SPEED,
    };
    let wait = lockstep.map(|_| mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT);
    let (m, url) = mock(speed, |b| b.lockstep(wait)).await;
    let o = FlyOptions {
        lockstep,
        ..opts(&url, mode, speed)
    };
    let r = fly_bounded(&test, &o, CancelToken::new()).await;
    let state = m.state();
    eprintln!(
        "{mode:?} mission {n}: {}",
        serde_json::to_string(&r).unwrap_or_default()
    );
    assert!(!state.armed, "{mode:?} mission {n}: still armed");
    m.shutdown().await.expect("mock stops");
    assert_flown(&r, &format!("{mode:?} mission {n}"));
    // It flew the whole mission: it ended at the land point.
    let land = test.mission.flight_path().last().copied().expect("land item");
    let end = r.trajectory.samples.last().copied().expect("samples");
    let off = (end.x - land.north_m).hypot(end.y - land.east_m);
    assert!(off < 3.0, "{mode:?} mission {n}: landed {off:.1} m from the land point");
    if mode != FlyMode::Mission {
        assert_eq!(
            r.status,
            Status::Landed,
            "{mode:?} mission {n} avoids the boxes: {:?}",
            r.reason
        );
    }
    // Only the avoidance companion answers requests; in lockstep it answers every one with a fresh plan.
    match (&r.companion_timing, mode) {
        (Some(t), FlyMode::Avoidance) => {
            let plans = t.plan_ms.expect("plans timed");
            assert!(
                t.request_to_answer_ms.n as f64 > r.flight_time_s,
                "{mode:?} mission {n}: {t:?}"
            );
            assert!(plans.n >= t.request_to_answer_ms.n / 2, "{t:?}");
            assert!(
                t.request_to_answer_ms.median >= plans.median * 0.5,
                "an answer waits for its plan: {t:?}"
            );
        }
        (None, FlyMode::Avoidance) => panic!("avoidance mission {n}: no companion timing"),
        (t, _) => assert!(t.is_none(), "{mode:?} has no companion: {t:?}"),
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

/// GF_ACTION is warning-only during the flight and PX4's default (2, Hold) again afterwards.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn geofence_action_is_restored_after_the_flight() {
    use prgenuav::bridge::wire::exchange::{RetryPolicy, Target};
    use prgenuav::bridge::wire::link::{Link, MavTransport};
    use prgenuav::bridge::wire::params::ParamSet;
    let test = generated(1);
    let (m, url) = mock(SPEED, |b| b).await;
    let r = fly_bounded(&test, &opts(&url, FlyMode::Mission, SPEED), CancelToken::new()).await;
    assert!(r.fence_uploaded && r.status.completed(), "{:?}", r.reason);
    // The breach is reported as PX4 v1.14 does (tab trimmed), and the mission went on (completed, not held).
    for text in ["Preflight Fail: Geofence violation", "Failsafe activated"] {
        assert!(
            r.warnings.iter().any(|w| w.starts_with(text)),
            "{text}: {:?}",
            r.warnings
        );
    }
    let addr = url.trim_start_matches("udpout:").to_string();
    let t = MavTransport::open(&format!("udpout:{addr}")).await.expect("link");
    let link = Link::new(
        std::sync::Arc::new(t),
        prgenuav::bridge::wire::clock::VehicleClock::new(SPEED),
    );
    let target = Target {
        system: 1,
        component: 1,
    };
    // Setting the value it should already have reports the value it had.
    let p = ParamSet::new(target, vec![("GF_ACTION".into(), 2.0)], RetryPolicy::PARAM);
    let changes = tokio::time::timeout(WALL_LIMIT, link.exchange(p, &CancelToken::new()))
        .await
        .expect("bounded")
        .expect("read back");
    assert_eq!(changes[0].old, 2.0, "GF_ACTION restored");
    m.shutdown().await.expect("mock stops");
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

/// The airborne part of a flight, times from the first sample off the ground.
fn airborne(t: &Trajectory) -> Vec<[f64; 4]> {
    let first = t.samples.iter().position(|s| s.z > 0.05).unwrap_or(0);
    let last = t.samples.iter().rposition(|s| s.z > 0.05).unwrap_or(0);
    let air = t.samples.get(first..=last).unwrap_or_default();
    let t0 = air.first().map_or(0.0, |s| s.t_s);
    // Whole milliseconds: the flights start at different times since boot, and t - t0 rounds differently.
    air.iter()
        .map(|s| [((s.t_s - t0) * 1000.0).round(), s.x, s.y, s.z])
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lockstep_flights_are_repeatable_and_never_mirror() {
    // 200x is far more than a debug-build planner can follow free-running; lockstep makes the mock wait.
    let speed = 200.0;
    let test = generated(2);
    let mut flights = Vec::new();
    for _ in 0..2 {
        let wait = Some(mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT);
        let (m, url) = mock(speed, |b| b.lockstep(wait)).await;
        let o = FlyOptions {
            lockstep: Some(Duration::from_millis(100)),
            ..opts(&url, FlyMode::Avoidance, speed)
        };
        let r = fly_bounded(&test, &o, CancelToken::new()).await;
        m.shutdown().await.expect("mock stops");
        assert_flown(&r, "lockstep");
        assert_eq!(r.status, Status::Landed, "{:?}", r.reason);
        assert!(r.warnings.iter().all(|w| !w.contains("mirrored")), "{:?}", r.warnings);
        flights.push(r);
    }
    let (a, b) = (airborne(&flights[0].trajectory), airborne(&flights[1].trajectory));
    assert!(a.len() > 100, "{} airborne samples", a.len());
    let first_difference = a.iter().zip(&b).position(|(x, y)| x != y);
    assert_eq!(
        (first_difference, a.len()),
        (None, b.len()),
        "the same test flies the same path, bit for bit (first difference: {:?} vs {:?})",
        first_difference.map(|i| a[i]),
        first_difference.map(|i| b[i]),
    );
    // The competition's binned distance depends on when recording began; the raw one only on the path.
    assert_eq!(flights[0].min_distance_raw, flights[1].min_distance_raw);
}

/// The status of mission 2 (generated obstacles) in avoidance mode with `faults`.
async fn avoidance_status(faults: Faults) -> FlightReport {
    let test = generated(2);
    let (m, url) = mock(PLANNED_SPEED, |b| b.faults(faults)).await;
    let r = fly_bounded(
        &test,
        &opts(&url, FlyMode::Avoidance, PLANNED_SPEED),
        CancelToken::new(),
    )
    .await;
    m.shutdown().await.expect("mock stops");
    r
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn loss_and_latency_give_the_same_status() {
    let clean = avoidance_status(Faults::default()).await;
    let lossy = avoidance_status(Faults {
        seed: 7,
        loss: 0.2,
        latency: Duration::from_millis(100),
        ..Faults::default()
    })
    .await;
    assert_eq!(clean.status, Status::Landed, "{:?}", clean.reason);
    assert_eq!(lossy.status, clean.status, "{:?} {:?}", lossy.reason, lossy.warnings);
    assert!(lossy.link.retries > 0, "20 % loss needs retries");
    // Free-running, answers go out at 10 Hz with the latest plan: its age is reported beside the latency.
    let t = clean.companion_timing.expect("companion timing");
    assert!(t.plan_age_ms.is_some_and(|a| a.n > 10), "{t:?}");
    assert!(lossy.samples > 100);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn refusals_are_rejected_with_the_reason() {
    let test = generated(1);
    let (m, url) = mock(SPEED, |b| {
        b.reject_mission(Some(MavMissionResult::MAV_MISSION_NO_SPACE))
    })
    .await;
    let r = fly_bounded(&test, &opts(&url, FlyMode::Mission, SPEED), CancelToken::new()).await;
    m.shutdown().await.expect("mock stops");
    assert_eq!(r.status, Status::Rejected);
    let why = r.reason.unwrap_or_default();
    assert!(
        why.contains("refused the mission upload") && why.contains("storage"),
        "{why}"
    );
    assert_eq!(r.samples, 0);

    let (m, url) = mock(SPEED, |b| b.fail_arm(true)).await;
    let r = fly_bounded(&test, &opts(&url, FlyMode::Mission, SPEED), CancelToken::new()).await;
    m.shutdown().await.expect("mock stops");
    assert_eq!(r.status, Status::Rejected);
    let why = r.reason.unwrap_or_default();
    assert!(
        why.starts_with("arming") && why.contains("TEMPORARILY_REJECTED"),
        "{why}"
    );
    assert!(
        r.warnings.iter().any(|w| w.contains("Arming denied")),
        "{:?}",
        r.warnings
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn reboot_and_silence_are_a_lost_link_with_the_recording_kept() {
    let test = generated(2);
    for (faults, words) in [
        (
            Faults {
                reboot_after: Some(Duration::from_secs(20)),
                ..Faults::default()
            },
            "rebooted",
        ),
        (
            Faults {
                silence_after: Some(Duration::from_secs(20)),
                ..Faults::default()
            },
            "no message",
        ),
    ] {
        let (m, url) = mock(SPEED, |b| b.faults(faults)).await;
        let r = fly_bounded(&test, &opts(&url, FlyMode::Mission, SPEED), CancelToken::new()).await;
        m.shutdown().await.expect("mock stops");
        assert_eq!(r.status, Status::LinkLost, "{:?}", r.reason);
        assert!(r.reason.as_deref().unwrap_or("").contains(words), "{:?}", r.reason);
        assert!(
            r.samples > 50 && r.flight_time_s > 3.0,
            "partial flight kept: {} samples",
            r.samples
        );
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancel_mid_flight_lands_and_keeps_the_partial_trajectory() {
    let test = generated(3);
    let (m, url) = mock(SPEED, |b| b).await;
    let dir = tempfile::tempdir().expect("temp dir");
    let csv = dir.path().join("flight.csv");
    let mut o = opts(&url, FlyMode::Avoidance, SPEED);
    o.trajectory_csv = Some(csv.clone());
    let cancel = CancelToken::new();
    let mut state = m.watch_state();
    let flight = tokio::spawn({
        let cancel = cancel.clone();
        async move { fly(&test, &o, cancel).await }
    });
    // Cancel once the vehicle is well airborne and moving.
    tokio::time::timeout(WALL_LIMIT, state.wait_for(|s| s.armed && s.pos_ned.z < -8.0))
        .await
        .expect("airborne in time")
        .expect("mock alive");
    cancel.cancel();
    let r = tokio::time::timeout(WALL_LIMIT, flight)
        .await
        .expect("ends in time")
        .expect("joined")
        .expect("flight runs");
    assert_eq!(r.status, Status::Aborted);
    assert!(
        r.warnings.iter().any(|w| w.contains("MAV_CMD_NAV_LAND sent")),
        "{:?}",
        r.warnings
    );
    let mode = m.state().mode;
    assert_eq!(mode, mock_autopilot::FlightMode::Land, "the vehicle is landing");
    m.shutdown().await.expect("mock stops");
    let kept = Trajectory::load_csv(&csv).expect("partial trajectory on disk");
    assert!(kept.samples.len() > 50);
    assert_eq!(kept.samples.len(), r.samples);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn no_vehicle_is_a_clear_error_in_bounded_time() {
    // A bound UDP socket that never answers.
    let quiet = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind");
    let url = format!("udpout:127.0.0.1:{}", quiet.local_addr().expect("addr").port());
    let mut o = opts(&url, FlyMode::Mission, 100.0);
    o.heartbeat_wait_s = 5.0;
    let e = tokio::time::timeout(WALL_LIMIT, fly(&case(1), &o, CancelToken::new()))
        .await
        .expect("bounded")
        .expect_err("no vehicle");
    assert!(e.to_string().contains("no autopilot heartbeat"), "{e}");
    let mut bad = o.clone();
    bad.connect = "udpin:0.0.0.0".into();
    let e = fly(&case(1), &bad, CancelToken::new()).await.expect_err("bad address");
    assert!(e.to_string().contains("no :PORT"), "{e}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_same_flight_over_a_serial_link() {
    let cable = super::pty::SerialCable::new().expect("pseudo-terminals");
    let test = generated(2);
    // In lockstep, as over TCP below: at 57600 baud the answers of a companion starved of CPU (a loaded test
    // machine) would otherwise arrive late enough to decide the flight.
    let m = MockAutopilot::builder()
        .link(LinkSpec::Address(format!("serial:{}:57600", cable.b)))
        .speed_factor(SpeedFactor::Times(PLANNED_SPEED))
        .lockstep(Some(mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT))
        .spawn()
        .await
        .expect("mock on serial");
    let o = FlyOptions {
        lockstep: Some(Duration::ZERO),
        ..opts(&format!("serial:{}:57600", cable.a), FlyMode::Avoidance, PLANNED_SPEED)
    };
    let r = fly_bounded(&test, &o, CancelToken::new()).await;
    m.shutdown().await.expect("mock stops");
    assert_flown(&r, "serial");
    assert_eq!(r.status, Status::Landed, "{:?}", r.reason);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_same_flight_over_tcp_in_lockstep() {
    // rust-mavlink's tcpin cannot report an ephemeral port: take a free one from the OS first.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port();
    let speed = 100.0;
    let spawn = tokio::spawn(
        MockAutopilot::builder()
            .link(LinkSpec::Address(format!("tcpin:127.0.0.1:{port}")))
            .speed_factor(SpeedFactor::Times(speed))
            .lockstep(Some(mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT))
            .spawn(),
    );
    let o = FlyOptions {
        lockstep: Some(Duration::ZERO),
        ..opts(&format!("tcpout:127.0.0.1:{port}"), FlyMode::Avoidance, speed)
    };
    let r = fly_bounded(&generated(2), &o, CancelToken::new()).await;
    let m = tokio::time::timeout(WALL_LIMIT, spawn)
        .await
        .expect("mock started in time")
        .expect("mock task")
        .expect("mock on tcp");
    m.shutdown().await.expect("mock stops");
    assert_flown(&r, "tcp");
    assert_eq!(r.status, Status::Landed, "{:?}", r.reason);
}

#[test]
fn fly_cli_checks_arguments_and_writes_the_world() {
    let (code, _, err) = super::prgenuav(&["fly", "missions/mission2.yaml", "--connect", "udp-in:14540"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("unknown scheme \"udp-in\""), "{err}");
    let (_dir, test) = super::test_file(2, super::valid_pair());
    let world = test.with_file_name("scene.world");
    let (code, _, err) = super::prgenuav(&[
        "fly",
        test.to_str().expect("utf-8 path"),
        "--world",
        world.to_str().expect("utf-8 path"),
        "--world-only",
    ]);
    assert_eq!(code, 0, "{err}");
    let sdf = std::fs::read_to_string(&world).expect("world written");
    assert!(sdf.contains("obstacle_0") && sdf.contains("obstacle_1") && !sdf.contains("obstacle_2"));
    let (code, _, err) = super::prgenuav(&["fly", "missions/mission2.yaml", "--world-only"]);
    assert_eq!(code, 2, "--world-only needs --world: {err}");
}

/// A timeout in avoidance mode ends with LAND, and the companion lands the vehicle as PX4-Avoidance would
/// (PX4 1.14 kept bouncing at 0-0.7 m with a companion that answered landing with a position): the bridge
/// follows it until it has landed and disarmed, recording all the way.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_timeout_lands_and_disarms_the_vehicle() {
    let test = generated(2);
    let (m, url) = mock(LOCKSTEP_SPEED, |b| {
        b.lockstep(Some(mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT))
    })
    .await;
    let o = FlyOptions {
        lockstep: Some(Duration::ZERO),
        timeout_s: 25.0,
        ..opts(&url, FlyMode::Avoidance, LOCKSTEP_SPEED)
    };
    let r = fly_bounded(&test, &o, CancelToken::new()).await;
    let state = m.state();
    m.shutdown().await.expect("mock stops");
    assert_eq!(r.status, Status::Timeout, "{:?}", r.reason);
    assert!(
        r.warnings.iter().any(|w| w.contains("landed and disarmed after LAND")),
        "{:?}",
        r.warnings
    );
    assert!(!state.armed, "disarmed");
    let end = r.trajectory.samples.last().copied().expect("samples");
    assert!(end.z < 0.3, "recorded down to the ground: {end:?}");
}

/// A flight on a `udpin` address lets go of its port before `fly` returns, so the vehicle's next flight can
/// bind it at once. (A PX4 SITL campaign lost both vehicles to `AddrInUse`: the last link's aborted tasks were
/// dropped only when the runtime next polled them.) On a current-thread runtime that poll never comes before
/// the bind below, so the test fails on a bridge that only aborts its tasks.
#[tokio::test(flavor = "current_thread")]
async fn a_flight_on_udpin_lets_go_of_its_port_before_it_returns() {
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("a free port")
        .port();
    let ours: std::net::SocketAddr = format!("127.0.0.1:{port}").parse().expect("addr");
    let mock = MockAutopilot::builder()
        .link(LinkSpec::UdpOut {
            bind: "127.0.0.1:0".parse().expect("addr"),
            remote: ours,
        })
        .speed_factor(SpeedFactor::Times(SPEED))
        .spawn()
        .await
        .expect("mock starts");
    let url = format!("udpin:{ours}");
    for flight in 1..=2 {
        let r = fly_bounded(&generated(2), &opts(&url, FlyMode::Mission, SPEED), CancelToken::new()).await;
        assert_flown(&r, &format!("flight {flight}"));
        let again = std::net::UdpSocket::bind(ours);
        assert!(again.is_ok(), "flight {flight}: port still held: {:?}", again.err());
    }
    drop(mock);
}
