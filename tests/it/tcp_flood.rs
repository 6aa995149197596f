//! A `tcpin` link that others reach first: an idle client and one that babbles garbage and a ground station's
//! heartbeats connect before the vehicle. The flight flies with the vehicle, the others hear nothing, and with
//! no vehicle at all the wait ends with a clear error in bounded time (rust-mavlink's own `tcpin` waits for
//! its first client without a deadline).

use std::io::{Read, Write};
use std::net::TcpStream;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use mavlink::dialects::common::{HEARTBEAT_DATA, MavAutopilot, MavMessage, MavModeFlag, MavState, MavType};
use mavlink::{MavHeader, MavlinkVersion};
use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, fly};

use super::{case, valid_pair};

const WALL_LIMIT: Duration = Duration::from_secs(90);

fn free_tcp_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

/// A ground station's heartbeat (system 77): valid MAVLink that is not the vehicle.
fn ground_station() -> Vec<u8> {
    let msg = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_GCS,
        autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_ACTIVE,
        mavlink_version: 3,
    });
    let header = MavHeader {
        system_id: 77u8.into(),
        component_id: 190,
        sequence: 0,
    };
    let mut bytes = Vec::new();
    mavlink::write_versioned_msg(&mut bytes, MavlinkVersion::V2, header, &msg).expect("encodes");
    bytes
}

/// Connects to `port` once the bridge listens (it binds when the flight starts).
fn connect(port: u16) -> TcpStream {
    let t0 = Instant::now();
    loop {
        match TcpStream::connect(("127.0.0.1", port)) {
            Ok(s) => return s,
            Err(e) => assert!(t0.elapsed() < Duration::from_secs(10), "the bridge never listened: {e}"),
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A client that connects first and babbles until `stop`; returns the bytes the bridge sent it.
fn babbler(port: u16, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<usize> {
    let mut stream = connect(port);
    std::thread::spawn(move || {
        stream
            .set_read_timeout(Some(Duration::from_millis(5)))
            .expect("timeout");
        let (mut heard, mut buf) = (0usize, [0u8; 2048]);
        while !stop.load(Ordering::Relaxed) {
            // A closed connection ends the babble: the bridge chose another client.
            if stream.write_all(&[0xfd; 120]).is_err() || stream.write_all(&ground_station()).is_err() {
                break;
            }
            match stream.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => heard += n,
                Err(_) => {}
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        heard
    })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_flight_on_tcpin_flies_with_the_vehicle_not_the_clients_that_came_first() {
    let port = free_tcp_port();
    let speed = 20.0;
    let opts = FlyOptions {
        connect: format!("tcpin:127.0.0.1:{port}"),
        mode: FlyMode::Mission,
        time_scale: speed,
        heartbeat_wait_s: 20.0,
        ..FlyOptions::default()
    };
    let test = case(2).with_obstacles(valid_pair());
    let flight = tokio::spawn(async move { fly(&test, &opts, CancelToken::new()).await });
    let idle = tokio::task::spawn_blocking(move || connect(port))
        .await
        .expect("idle client");
    let stop = Arc::new(AtomicBool::new(false));
    let babble = babbler(port, stop.clone());
    std::thread::sleep(Duration::from_millis(300));
    let mock = MockAutopilot::builder()
        .link(LinkSpec::Address(format!("tcpout:127.0.0.1:{port}")))
        .speed_factor(SpeedFactor::Times(speed))
        .spawn()
        .await
        .expect("mock starts");
    let r = tokio::time::timeout(WALL_LIMIT, flight).await;
    stop.store(true, Ordering::Relaxed);
    let heard = babble.join().expect("babbler");
    drop((mock, idle));
    let r = r
        .expect("the flight ends in bounded time")
        .expect("joined")
        .expect("a report");
    assert!(r.status.completed(), "{:?}: {:?} {:?}", r.status, r.reason, r.warnings);
    assert_eq!(
        heard, 0,
        "the bridge sent its commands to a client that is not the vehicle"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn waiting_on_tcpin_without_a_vehicle_ends_with_a_clear_error() {
    let port = free_tcp_port();
    let opts = FlyOptions {
        connect: format!("tcpin:127.0.0.1:{port}"),
        mode: FlyMode::Mission,
        heartbeat_wait_s: 3.0,
        ..FlyOptions::default()
    };
    let stop = Arc::new(AtomicBool::new(false));
    let t0 = Instant::now();
    let waiting = tokio::spawn(async move { fly(&case(1), &opts, CancelToken::new()).await });
    let babble = babbler(port, stop.clone());
    let r = tokio::time::timeout(WALL_LIMIT, waiting).await;
    stop.store(true, Ordering::Relaxed);
    assert_eq!(babble.join().expect("babbler"), 0);
    let e = r
        .expect("bounded")
        .expect("joined")
        .expect_err("no vehicle")
        .to_string();
    assert!(e.contains("no autopilot heartbeat"), "{e}");
    assert!(t0.elapsed() < Duration::from_secs(15), "{:?}", t0.elapsed());
}
