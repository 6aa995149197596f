//! One frame for judge, planner and obstacles, against the mock on ephemeral ports: a second flight on one
//! instance (it starts where the first landed), a vehicle whose EKF origin is metres from the test's home, and a
//! vehicle kilometres away (refused, or re-anchored at its home). The judged distance is compared with the
//! mock's own true positions, put into the test's frame by projecting them about the test's home here, not by
//! the bridge's frame code.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use mock_autopilot::{LinkSpec, MockAutopilot, MockHandle, SpeedFactor};
use prgenuav::bridge::companion::frame::FrameSource;
use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, Status, fly};
use prgenuav::judge::{Judge, judge_in_frame};
use prgenuav::model::{GeoPoint, LocalProjection, Obstacle, SIM_HOME, Sample, TestCase, Trajectory};

use super::case;

const SPEED: f64 = 20.0;
const WALL_LIMIT: Duration = Duration::from_secs(60);

async fn mock_at(boot: GeoPoint) -> (MockHandle, String) {
    mock_at_speed(boot, SPEED).await
}

async fn mock_at_speed(boot: GeoPoint, speed: f64) -> (MockHandle, String) {
    let m = MockAutopilot::builder()
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(SpeedFactor::Times(speed))
        .home(boot)
        .spawn()
        .await
        .expect("mock starts");
    let port = m.local_addr().expect("udp").port();
    (m, format!("udpout:127.0.0.1:{port}"))
}

fn opts(url: &str) -> FlyOptions {
    FlyOptions {
        connect: url.into(),
        mode: FlyMode::Mission,
        time_scale: SPEED,
        heartbeat_wait_s: 20.0,
        judge: Judge::E2025,
        ..FlyOptions::default()
    }
}

/// A point `north_m`, `east_m` from `p`.
fn shifted(p: GeoPoint, north_m: f64, east_m: f64) -> GeoPoint {
    let (lat_deg, lon_deg) = LocalProjection::new(p).unproject(north_m, east_m);
    GeoPoint { lat_deg, lon_deg, ..p }
}

/// Flies `test` while recording the mock's true positions, converted into the frame about `frame_home` with the
/// mock's own projection (not the bridge's code). Returns the report, the true path and whether it ever armed.
async fn fly_with_truth(
    m: &MockHandle,
    boot: GeoPoint,
    frame_home: GeoPoint,
    test: &TestCase,
    o: &FlyOptions,
) -> (FlightReport, Trajectory, bool) {
    let mut watch = m.watch_state();
    let (vehicle, home) = (LocalProjection::new(boot), LocalProjection::new(frame_home));
    let seen: Arc<Mutex<(Vec<Sample>, bool)>> = Arc::default();
    let sink = Arc::clone(&seen);
    let truth = tokio::spawn(async move {
        while watch.changed().await.is_ok() {
            let s = *watch.borrow_and_update();
            let mut out = sink.lock().expect("lock");
            out.1 |= s.armed;
            if !s.armed {
                continue;
            }
            let (lat, lon) = vehicle.unproject(s.pos_ned.x, s.pos_ned.y);
            let (x, y) = home.project(lat, lon);
            let t_s = s.sim_time.as_secs_f64();
            out.0.push(Sample {
                t_s,
                x,
                y,
                z: -s.pos_ned.z,
                r: None,
            });
        }
    });
    let report = tokio::time::timeout(WALL_LIMIT, fly(test, o, CancelToken::new()))
        .await
        .expect("flight within the wall-time limit")
        .expect("flight runs");
    truth.abort();
    let (samples, armed) = std::mem::take(&mut *seen.lock().expect("lock"));
    (report, Trajectory::new(samples), armed)
}

/// The bridge's judged distance equals the true path's in the test's frame, and so does the collision verdict.
fn assert_judged_like_truth(r: &FlightReport, obstacles: &[Obstacle], truth: &Trajectory, what: &str) {
    assert!(r.status.completed(), "{what}: {:?} {:?}", r.status, r.reason);
    let t = judge_in_frame(truth, obstacles, Judge::E2025).expect("truth judged");
    let got = r.min_distance_raw.expect("judged");
    assert!(
        (got - t.min_distance_raw).abs() < 0.15,
        "{what}: bridge {got:.3} m, true {:.3} m",
        t.min_distance_raw
    );
    assert_eq!(
        r.status == Status::Collision,
        t.collision,
        "{what}: {:?} {:?}",
        r.status,
        r.reason
    );
    assert_eq!(r.frame, "test_home_ned");
    assert_eq!(r.frame_source, Some(FrameSource::GpsGlobalOrigin), "{what}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn second_flight_on_one_instance_is_judged_where_it_flew() {
    let (m, url) = mock_at(SIM_HOME).await;
    let plain = case(2);
    // Flight 1: mission 2 goes East and lands 12 m South of home.
    let (r1, _, _) = fly_with_truth(&m, SIM_HOME, SIM_HOME, &plain, &opts(&url)).await;
    assert_eq!(r1.status, Status::Landed, "{:?}", r1.reason);
    let landed = m.state().pos_ned;
    assert!(landed.x < -8.0, "mission 2 lands South of home: {landed:?}");
    // Flight 2 starts there; a box on its true outbound leg (half way to the waypoint), which the path
    // origin-aligned to its first sample would miss by the 12 m it starts away from home.
    let wp = plain.mission.flight_path()[1];
    let mid = ((landed.x + wp.north_m) / 2.0, (landed.y + wp.east_m) / 2.0);
    let test = plain.with_obstacles(vec![Obstacle::new(2.0, 2.0, 20.0, mid.0, mid.1, 0.0)]);
    let (r2, truth, _) = fly_with_truth(&m, SIM_HOME, SIM_HOME, &test, &opts(&url)).await;
    m.shutdown().await.expect("mock stops");
    let first = r2.trajectory.samples.first().copied().expect("samples");
    assert!(
        (first.x - landed.x).hypot(first.y - landed.y) < 0.5,
        "recorded from where it landed, not from the origin: {first:?} vs {landed:?}"
    );
    let offset = r2.frame_origin_offset_m.expect("frame measured");
    assert!(
        offset[0].hypot(offset[1]) < 0.05,
        "the EKF origin stays at boot: {offset:?}"
    );
    assert_judged_like_truth(&r2, &test.obstacles, &truth, "second flight");
    assert_eq!(
        r2.status,
        Status::Collision,
        "mission mode flies through the box: {:?}",
        r2.reason
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ekf_origin_metres_from_the_test_home_is_no_false_collision() {
    // The vehicle boots (and keeps its EKF origin) 6 m North of the test's home.
    let boot = shifted(SIM_HOME, 6.0, 0.0);
    let (m, url) = mock_at(boot).await;
    let plain = case(2);
    // A box 6 m South of the true return leg's middle: where a path aligned to its first sample would fly.
    let path = plain.mission.flight_path();
    let (wp, land) = (path[1], path[2]);
    let mid = ((wp.north_m + land.north_m) / 2.0 - 6.0, (wp.east_m + land.east_m) / 2.0);
    let test = plain.with_obstacles(vec![Obstacle::new(2.0, 2.0, 20.0, mid.0, mid.1, 0.0)]);
    let (r, truth, _) = fly_with_truth(&m, boot, SIM_HOME, &test, &opts(&url)).await;
    m.shutdown().await.expect("mock stops");
    let offset = r.frame_origin_offset_m.expect("frame measured");
    assert!(
        (offset[0] - 6.0).abs() < 0.05 && offset[1].abs() < 0.05,
        "EKF origin in the test's frame: {offset:?}"
    );
    assert_judged_like_truth(&r, &test.obstacles, &truth, "origin 6 m North");
    assert_eq!(r.status, Status::Landed, "{:?}", r.reason);
    assert!(r.min_distance_raw.is_some_and(|d| d > 3.0), "{:?}", r.min_distance_raw);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_vehicle_far_away_is_refused_unless_the_test_is_anchored_at_its_home() {
    // 2.2 km North of the test's home: beyond PX4's MIS_DIST_1WP default of 900 m.
    let boot = shifted(SIM_HOME, 2200.0, 0.0);
    let (m, url) = mock_at(boot).await;
    let test = super::case(2).with_obstacles(vec![Obstacle::new(2.0, 2.0, 20.0, 2.0, 27.0, 0.0)]);
    let (r, _, armed) = fly_with_truth(&m, boot, SIM_HOME, &test, &opts(&url)).await;
    assert_eq!(r.status, Status::Rejected);
    let reason = r.reason.clone().unwrap_or_default();
    assert!(
        reason.contains("--anchor-at-vehicle-home") && reason.contains("MIS_DIST_1WP"),
        "{reason}"
    );
    let p = r.placement.clone().expect("placement reported");
    assert!(p.too_far && !p.anchored && (p.distance_m - 2200.0).abs() < 1.0, "{p:?}");
    assert_eq!(p.mis_dist_1wp_m, Some(900.0));
    assert!(!armed, "never armed");
    assert_eq!(m.state().mission_items, 0, "nothing uploaded");

    // Anchored: the same test flies about the vehicle's home and is judged in that frame.
    let o = FlyOptions {
        anchor_at_vehicle_home: true,
        ..opts(&url)
    };
    let anchored = test.anchored_at(boot);
    let (r, truth, _) = fly_with_truth(&m, boot, boot, &anchored, &opts(&url)).await;
    // (the pre-anchored test flown plainly is the reference for what anchoring must do)
    assert_judged_like_truth(&r, &anchored.obstacles, &truth, "pre-anchored reference");
    let reference = r.min_distance_raw;
    let (r, truth, _) = fly_with_truth(&m, boot, boot, &test, &o).await;
    m.shutdown().await.expect("mock stops");
    let p = r.placement.clone().expect("placement reported");
    assert!(p.anchored && !p.too_far, "{p:?}");
    assert_judged_like_truth(&r, &test.obstacles, &truth, "anchored");
    let d = r.min_distance_raw.expect("judged");
    assert!((d - reference.unwrap_or(f64::NAN)).abs() < 0.15, "{d} vs {reference:?}");
    // The box's centre is printed about the vehicle's home.
    let c = p.obstacle_centres[0];
    let (n, e) = LocalProjection::new(boot).project(c.lat_deg, c.lon_deg);
    assert!((n - 2.0).abs() < 0.01 && (e - 27.0).abs() < 0.01, "{n} {e}");
}

/// `case(2)` with `obstacles`, saved where the CLI can read it (the mission path resolves from the repo root).
fn saved_test(dir: &std::path::Path, obstacles: Vec<Obstacle>) -> String {
    let path = dir.join("test.yaml");
    case(2)
        .with_obstacles(obstacles)
        .save(&path, prgenuav::model::Spelling::Old)
        .expect("test written");
    path.display().to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fly_cli_exits_2_for_a_far_vehicle_and_prints_the_boxes_when_anchored() {
    let boot = shifted(SIM_HOME, 2200.0, 0.0);
    // A separate process under a loaded CI machine: a slower clock keeps wall-time hiccups short in vehicle time.
    let (m, url) = mock_at_speed(boot, 10.0).await;
    let dir = tempfile::tempdir().expect("tempdir");
    let test = saved_test(dir.path(), vec![Obstacle::new(2.0, 2.0, 20.0, 2.0, 27.0, 0.0)]);
    let run = |extra: &'static [&'static str]| {
        let (test, url) = (test.clone(), url.clone());
        tokio::task::spawn_blocking(move || {
            let mut args = vec![
                "fly",
                &test,
                "--connect",
                &url,
                "--mode",
                "mission",
                "--time-scale",
                "10",
            ];
            args.extend(["--json", "--no-fence"]);
            args.extend(extra);
            super::prgenuav(&args)
        })
    };
    let (code, out, _) = tokio::time::timeout(WALL_LIMIT, run(&["--quiet"]))
        .await
        .expect("bounded")
        .expect("ran");
    assert_eq!(code, 2, "{out}");
    let json: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert_eq!(json["status"], "rejected");
    // Who flew and which model predicted it, also with --quiet.
    assert_eq!(json["vehicle"]["autopilot"], "PX4", "{json}");
    assert_eq!(json["vehicle"]["vehicle_type"], "quadrotor", "{json}");
    assert_eq!(json["vehicle"]["flight_software"], "1.14.0", "{json}");
    assert_eq!(json["lfs_motion_model"], "px4", "{json}");
    assert!(
        json["reason"]
            .as_str()
            .unwrap_or("")
            .contains("--anchor-at-vehicle-home"),
        "{json}"
    );
    let (code, out, err) = tokio::time::timeout(
        WALL_LIMIT,
        run(&["--anchor-at-vehicle-home", "--judge", "2025", "--no-predict"]),
    )
    .await
    .expect("bounded")
    .expect("ran");
    m.shutdown().await.expect("mock stops");
    assert_eq!(code, 0, "{out}\n{err}");
    assert!(err.contains("box 0 centre now at"), "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert_eq!(
        (&json["judge"], &json["frame"]),
        (&"2025".into(), &"test_home_ned".into())
    );
    assert_eq!(json["frame_source"], "gps_global_origin");
    assert_eq!(json["placement"]["anchored"], true);
    assert_eq!(
        json["lfs_motion_model"],
        serde_json::Value::Null,
        "no prediction, no model"
    );
}

#[test]
fn old_rule_tests_are_simulated_with_a_warning_unless_strict() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A 10 m high box: older editions allowed it, the current rules want it taller than the flight altitude.
    let test = saved_test(dir.path(), vec![Obstacle::new(2.0, 2.0, 10.0, -6.0, 27.0, 0.0)]);
    let (code, out, err) = super::prgenuav(&["simulate", &test, "--json", "--judge", "2025"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning") && err.contains("size.h") && err.contains("--strict"),
        "{err}"
    );
    let json: serde_json::Value = serde_json::from_str(&out).expect("json");
    assert_eq!(json["judge"], "2025");
    let (code, _, err) = super::prgenuav(&["simulate", &test, "--strict"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("violation"), "{err}");
    let (code, _, err) = super::prgenuav(&["simulate", &test, "--judge", "2024"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("possible values: 2026, 2025"), "{err}");
}
