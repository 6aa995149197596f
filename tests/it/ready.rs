//! On the mock: the bridge waits for a vehicle that is still settling after boot, refuses a mission
//! the vehicle's navigator rejects before arming (with the vehicle's own words), and says at once when the
//! vehicle's clock disagrees with the time scale. Assertions go through the report's JSON, as users read it.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use mock_autopilot::{LinkSpec, MockAutopilot, MockHandle, SpeedFactor, VehicleConfig};
use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, fly};
use prgenuav::model::GeoPoint;

use super::case;

const WALL_LIMIT: Duration = Duration::from_secs(90);

async fn mock(speed: f64, cfg: VehicleConfig) -> (MockHandle, String) {
    let m = MockAutopilot::builder()
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(SpeedFactor::Times(speed))
        .vehicle(cfg)
        .spawn()
        .await
        .expect("mock starts");
    let port = m.local_addr().expect("udp").port();
    (m, format!("udpout:127.0.0.1:{port}"))
}

fn opts(url: &str, time_scale: f64) -> FlyOptions {
    FlyOptions {
        connect: url.into(),
        mode: FlyMode::Mission,
        time_scale,
        heartbeat_wait_s: 20.0,
        ..FlyOptions::default()
    }
}

async fn flown(o: &FlyOptions) -> (FlightReport, serde_json::Value) {
    let r = tokio::time::timeout(WALL_LIMIT, fly(&case(1), o, CancelToken::new()))
        .await
        .expect("flight within the wall-time limit")
        .expect("flight runs");
    let json = serde_json::to_value(&r).expect("report serialises");
    eprintln!("{json}");
    (r, json)
}

/// Records whether the mock was ever armed.
fn watch_armed(m: &MockHandle) -> Arc<AtomicBool> {
    let ever = Arc::new(AtomicBool::new(false));
    let mut rx = m.watch_state();
    let flag = ever.clone();
    tokio::spawn(async move {
        while rx.changed().await.is_ok() {
            if rx.borrow().armed {
                flag.store(true, Ordering::SeqCst);
            }
        }
    });
    ever
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn arming_waits_for_the_estimator_to_settle() {
    // 40 s of vehicle time after boot before PX4-like readiness: longer than any fixed retry.
    let settle = Duration::from_secs(40);
    let cfg = VehicleConfig {
        estimator_settle: settle,
        ..VehicleConfig::default()
    };
    let (m, url) = mock(20.0, cfg).await;
    let (_, json) = flown(&opts(&url, 20.0)).await;
    m.shutdown().await.expect("mock stops");
    assert_eq!(json["status"], "landed", "{}", json["reason"]);
    let waited = json["ready_wait_s"].as_f64().unwrap_or(0.0);
    assert!(waited > 20.0 && waited < 60.0, "ready_wait_s {waited}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_mission_the_navigator_rejects_is_never_armed_into() {
    // The vehicle boots 5335 km from the test's home (the competition's Zurich default): PX4's MIS_DIST_1WP.
    let cfg = VehicleConfig {
        home: GeoPoint {
            lat_deg: 0.0,
            lon_deg: 0.0,
            alt_m: 488.0,
        },
        estimator_settle: Duration::from_secs(2),
        ..VehicleConfig::default()
    };
    let (m, url) = mock(20.0, cfg).await;
    let armed = watch_armed(&m);
    let (_, json) = flown(&opts(&url, 20.0)).await;
    m.shutdown().await.expect("mock stops");
    assert_eq!(json["status"], "rejected");
    let reason = json["reason"].as_str().unwrap_or("");
    // The bridge's own MIS_DIST_1WP check (frame placement) refuses before anything is uploaded; PX4's
    // navigator wording is accepted too, for a vehicle that refuses by itself.
    assert!(
        (reason.contains("First waypoint too far away") && reason.contains("900 max"))
            || (reason.contains("MIS_DIST_1WP") && reason.contains("--anchor-at-vehicle-home")),
        "{reason}"
    );
    assert!(
        !armed.load(Ordering::SeqCst),
        "the vehicle was armed into a mission it refuses"
    );
    let said = json["vehicle_messages"].as_array().cloned().unwrap_or_default();
    assert!(
        !reason.contains("First waypoint")
            || said.iter().any(|m| m["severity"] == "critical"
                && m["text"]
                    .as_str()
                    .is_some_and(|t| t.starts_with("First waypoint too far away: "))
                && m["t_s"].is_number()),
        "{said:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_vehicle_clock_faster_than_the_time_scale_is_reported() {
    // The mock runs at 10x; the bridge is told 1x and gives up after 8 (wall = assumed vehicle) seconds.
    let cfg = VehicleConfig {
        estimator_settle: Duration::from_secs(5),
        ..VehicleConfig::default()
    };
    let (m, url) = mock(10.0, cfg).await;
    let o = FlyOptions {
        timeout_s: 8.0,
        ..opts(&url, 1.0)
    };
    let (_, json) = flown(&o).await;
    m.shutdown().await.expect("mock stops");
    let clock = &json["clock"];
    let rate = clock["measured_rate"].as_f64().unwrap_or(0.0);
    assert!((8.0..12.0).contains(&rate), "measured rate {rate}");
    assert_eq!(clock["time_scale"], 1.0);
    let w = clock["warning"].as_str().unwrap_or("");
    assert!(w.ends_with("use --time-scale 10"), "{clock}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_detected_clock_is_used() {
    let (m, url) = mock(10.0, VehicleConfig::default()).await;
    let o = FlyOptions {
        detect_time_scale: true,
        ..opts(&url, 1.0)
    };
    let (r, json) = flown(&o).await;
    m.shutdown().await.expect("mock stops");
    assert_eq!(json["status"], "landed", "{}", json["reason"]);
    assert_eq!(json["clock"]["time_scale"], 10.0, "{}", json["clock"]);
    assert_eq!(json["clock"]["detected"], true);
    assert!(json["clock"]["warning"].is_null(), "{}", json["clock"]);
    assert!(r.flight_time_s > 20.0);
}
