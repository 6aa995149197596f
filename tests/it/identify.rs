//! `fly` names the vehicle that answered before it uploads anything: system id, autopilot, type and version.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
use prgenuav::bridge::wire::notices::{Notice, NoticeSink};
use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, fly};

use super::{case, valid_pair};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_vehicle_that_answered_is_named_first() {
    let mock = MockAutopilot::builder()
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(SpeedFactor::Times(20.0))
        .spawn()
        .await
        .expect("mock starts");
    let port = mock.local_addr().expect("udp").port();
    let heard: Arc<Mutex<Vec<String>>> = Arc::default();
    let cancel = CancelToken::new();
    let (log, stop) = (heard.clone(), cancel.clone());
    let opts = FlyOptions {
        connect: format!("udpout:127.0.0.1:{port}"),
        mode: FlyMode::Mission,
        time_scale: 20.0,
        heartbeat_wait_s: 20.0,
        // Cancelled as soon as the vehicle is named: nothing after that matters here.
        notices: Some(NoticeSink::new(move |n: &Notice| {
            log.lock().expect("log").push(n.to_string());
            stop.cancel();
        })),
        ..FlyOptions::default()
    };
    let test = case(2).with_obstacles(valid_pair());
    let r = tokio::time::timeout(Duration::from_secs(60), fly(&test, &opts, cancel)).await;
    let report = r.expect("bounded").expect("a report of the stopped flight");
    mock.shutdown().await.expect("mock stops");
    let heard = heard.lock().expect("log").clone();
    assert_eq!(
        heard.first().map(String::as_str),
        Some("vehicle answered: system 1, component 1: PX4 quadrotor, flight software 1.14.0"),
        "{heard:?}"
    );
    let who = report.vehicle.expect("the report names the vehicle");
    assert_eq!(
        (who.system, who.autopilot.as_str(), who.flight_software.as_deref()),
        (1, "PX4", Some("1.14.0"))
    );
}
