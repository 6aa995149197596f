//! `--mode collision-prevention` against the in-process mock autopilot (Position mode, MANUAL_CONTROL sticks,
//! OBSTACLE_DISTANCE and Collision Prevention): the pilot flies the mission and lands, or gives up behind a
//! wall as a timeout with its reason; the verdict says whether the vehicle came inside CP_DIST.

use std::time::Duration;

use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, Status, fly};
use prgenuav::lfs::cp_model::waypoints;
use prgenuav::model::{Obstacle, TestCase};

use super::case;

/// Slow enough that the 20 Hz sticks (vehicle time) never gap on a loaded machine.
const SPEED: f64 = 4.0;

async fn fly_cp(test: &TestCase) -> FlightReport {
    let m = MockAutopilot::builder()
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(SpeedFactor::Times(SPEED))
        .spawn()
        .await
        .expect("mock starts");
    let port = m.local_addr().expect("udp").port();
    let o = FlyOptions {
        connect: format!("udpout:127.0.0.1:{port}"),
        mode: FlyMode::CollisionPrevention,
        time_scale: SPEED,
        heartbeat_wait_s: 20.0,
        ..FlyOptions::default()
    };
    let r = tokio::time::timeout(Duration::from_secs(240), fly(test, &o, CancelToken::new()))
        .await
        .expect("bounded")
        .expect("flies");
    m.shutdown().await.expect("mock stops");
    r
}

/// Mission 2 with `obstacles`, and its first leg's midpoint and direction (North, East).
fn mission2_with(obstacles: impl Fn([f64; 2], [f64; 2]) -> Vec<Obstacle>) -> TestCase {
    let c = case(2);
    let w = waypoints(&c.mission);
    let d = [w[1][0] - w[0][0], w[1][1] - w[0][1]];
    let n = d[0].hypot(d[1]);
    let mid = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
    let boxes = obstacles(mid, [d[0] / n, d[1] / n]);
    c.with_obstacles(boxes)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_wall_across_the_path_holds_the_vehicle_and_the_pilot_gives_up() {
    let test = mission2_with(|mid, dir| {
        // The long side perpendicular to the leg (the perpendicular's angle, within the rules' 0-90 degrees).
        let across = (dir[1].atan2(dir[0]).to_degrees() + 90.0)
            .rem_euclid(180.0)
            .rem_euclid(90.0);
        vec![Obstacle::new(18.0, 2.0, 20.0, mid[0], mid[1], across)]
    });
    let r = fly_cp(&test).await;
    eprintln!("{}", serde_json::to_string(&r).unwrap_or_default());
    assert_eq!(r.status, Status::Timeout, "{:?}", r.reason);
    let why = r.reason.clone().unwrap_or_default();
    assert!(why.contains("did not reach waypoint 2 of 3"), "{why}");
    let cp = r.collision_prevention.expect("a CP verdict");
    assert_eq!(cp.cp_dist_m, 2.0);
    let centre = cp.closest_centre_m.expect("measured");
    assert!(centre > 1.0 && centre < 3.0, "held near CP_DIST: {centre}");
    assert!(
        r.warnings.iter().any(|w| w.contains("landed and disarmed")),
        "{:?}",
        r.warnings
    );
    // The mock acts as PX4 v1.14, whose Collision Prevention ignores its default MPC_POS_MODE 4.
    assert!(
        r.warnings.iter().any(|w| w.contains("MPC_POS_MODE set to 3")),
        "{:?}",
        r.warnings
    );
}
