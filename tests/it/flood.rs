//! A flooded link: a peer sends the bridge's `udpin` port garbage and valid MAVLink of other systems (a
//! ground station's heartbeats, acknowledgements no one asked for) at a high rate, during a flight and while
//! the bridge waits for a vehicle. The flight completes and the wait ends with a clear error, both in bounded
//! time, with the process's memory bounded.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use mavlink::dialects::common::{
    COMMAND_ACK_DATA, HEARTBEAT_DATA, MISSION_ACK_DATA, MavAutopilot, MavCmd, MavMessage, MavMissionResult,
    MavMissionType, MavModeFlag, MavResult, MavState, MavType,
};
use mavlink::{MavHeader, MavlinkVersion};
use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, fly};

use super::{case, valid_pair};

/// Datagrams per burst, and the pause between bursts: about 20 000 datagrams a second.
const BURST: u64 = 200;
const PAUSE: Duration = Duration::from_millis(10);
/// No case may take longer (wall time).
const WALL_LIMIT: Duration = Duration::from_secs(90);

/// Valid MAVLink from system 77: messages that would fool a bridge that listened to anyone.
fn other_system(k: u64) -> Vec<u8> {
    let msg = match k % 3 {
        0 => MavMessage::HEARTBEAT(HEARTBEAT_DATA {
            custom_mode: 0,
            mavtype: MavType::MAV_TYPE_GCS,
            autopilot: MavAutopilot::MAV_AUTOPILOT_INVALID,
            base_mode: MavModeFlag::empty(),
            system_status: MavState::MAV_STATE_ACTIVE,
            mavlink_version: 3,
        }),
        1 => MavMessage::COMMAND_ACK(COMMAND_ACK_DATA {
            command: MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
            result: MavResult::MAV_RESULT_DENIED,
            ..Default::default()
        }),
        _ => MavMessage::MISSION_ACK(MISSION_ACK_DATA {
            target_system: 245,
            target_component: 190,
            mavtype: MavMissionResult::MAV_MISSION_ERROR,
            mission_type: MavMissionType::MAV_MISSION_TYPE_MISSION,
            ..Default::default()
        }),
    };
    let header = MavHeader {
        system_id: 77u8.into(),
        component_id: 1,
        sequence: k as u8,
    };
    let mut bytes = Vec::new();
    mavlink::write_versioned_msg(&mut bytes, MavlinkVersion::V2, header, &msg).expect("encodes");
    bytes
}

/// Floods `port` until `stop`: mostly garbage (MAVLink start bytes among random ones), every fourth datagram
/// another system's valid message. Returns the datagrams sent and those the bridge sent back to the flooder.
fn flood(port: u16, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<(u64, u64)> {
    std::thread::spawn(move || {
        let socket = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind");
        socket.set_nonblocking(true).expect("non-blocking");
        let (mut sent, mut answered, mut x) = (0u64, 0u64, 0x2545_f491_4f6c_dd1du64);
        let mut buf = [0u8; 2048];
        while !stop.load(Ordering::Relaxed) {
            for _ in 0..BURST {
                let datagram = if sent % 4 == 3 {
                    other_system(sent)
                } else {
                    // xorshift: garbage of 1 to 280 bytes, start bytes included.
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    (0..1 + x % 280)
                        .map(|i| [0xfd, 0xfe, (x >> (i % 56)) as u8][(i % 3) as usize])
                        .collect()
                };
                let _ = socket.send_to(&datagram, ("127.0.0.1", port));
                sent += 1;
            }
            while socket.recv_from(&mut buf).is_ok() {
                answered += 1;
            }
            std::thread::sleep(PAUSE);
        }
        (sent, answered)
    })
}

fn free_udp_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0")
        .and_then(|s| s.local_addr())
        .expect("a free port")
        .port()
}

/// This process's resident memory, kB.
fn rss_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next()?.parse().ok())
        .unwrap_or(0)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_flight_on_a_flooded_udpin_port_completes() {
    let port = free_udp_port();
    let ours: std::net::SocketAddr = format!("127.0.0.1:{port}").parse().expect("addr");
    let speed = 20.0;
    let mock = MockAutopilot::builder()
        .link(LinkSpec::UdpOut {
            bind: "127.0.0.1:0".parse().expect("addr"),
            remote: ours,
        })
        .speed_factor(SpeedFactor::Times(speed))
        .spawn()
        .await
        .expect("mock starts");
    let stop = Arc::new(AtomicBool::new(false));
    let flooder = flood(port, stop.clone());
    let rss_before = rss_kb();
    let opts = FlyOptions {
        connect: format!("udpin:{ours}"),
        mode: FlyMode::Mission,
        time_scale: speed,
        heartbeat_wait_s: 20.0,
        ..FlyOptions::default()
    };
    let t0 = Instant::now();
    let test = case(2).with_obstacles(valid_pair());
    let r = tokio::time::timeout(WALL_LIMIT, fly(&test, &opts, CancelToken::new())).await;
    stop.store(true, Ordering::Relaxed);
    let (sent, answered) = flooder.join().expect("flooder");
    let grown_kb = rss_kb().saturating_sub(rss_before);
    drop(mock);
    let r = r.expect("the flight ends in bounded time").expect("a report");
    eprintln!(
        "flooded flight: {:?} in {:.1} s wall, {sent} datagrams flooded ({answered} answered), {} messages ignored, {} received, RSS grew \
         {grown_kb} kB",
        r.status,
        t0.elapsed().as_secs_f64(),
        r.link.packets_ignored,
        r.link.packets_received
    );
    assert!(r.status.completed(), "{:?}: {:?} {:?}", r.status, r.reason, r.warnings);
    assert!(
        r.link.packets_ignored > 100,
        "the flood reached the bridge: {:?}",
        r.link
    );
    assert_eq!(answered, 0, "the bridge sent its commands to the flooder");
    assert!(grown_kb < 256 * 1024, "memory grew by {grown_kb} kB");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn waiting_for_a_vehicle_on_a_flooded_port_ends_with_a_clear_error() {
    let port = free_udp_port();
    let stop = Arc::new(AtomicBool::new(false));
    let flooder = flood(port, stop.clone());
    let opts = FlyOptions {
        connect: format!("udpin:127.0.0.1:{port}"),
        mode: FlyMode::Mission,
        heartbeat_wait_s: 3.0,
        ..FlyOptions::default()
    };
    let t0 = Instant::now();
    let r = tokio::time::timeout(WALL_LIMIT, fly(&case(1), &opts, CancelToken::new())).await;
    stop.store(true, Ordering::Relaxed);
    let (sent, answered) = flooder.join().expect("flooder");
    let e = r.expect("bounded").expect_err("no vehicle").to_string();
    assert!(e.contains("no autopilot heartbeat"), "{e}");
    assert!(t0.elapsed() < Duration::from_secs(15), "{:?}", t0.elapsed());
    assert!(sent > 1000, "{sent} datagrams");
    assert_eq!(answered, 0, "nothing is sent before a vehicle spoke");
}
