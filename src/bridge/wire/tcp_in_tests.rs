use std::time::Duration;

use mavlink::MavlinkVersion;
use mavlink::dialects::common::{HEARTBEAT_DATA, MavAutopilot, MavModeFlag, MavState, MavType};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::time::timeout;

use super::*;

fn heartbeat(system_id: u8, autopilot: MavAutopilot) -> Vec<u8> {
    let msg = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot,
        base_mode: MavModeFlag::empty(),
        system_status: MavState::MAV_STATE_STANDBY,
        mavlink_version: 3,
    });
    let header = MavHeader {
        system_id: system_id.into(),
        component_id: 1,
        sequence: 0,
    };
    let mut bytes = Vec::new();
    mavlink::write_versioned_msg(&mut bytes, MavlinkVersion::V2, header, &msg).unwrap();
    bytes
}

fn vehicle_heartbeat() -> Vec<u8> {
    heartbeat(1, MavAutopilot::MAV_AUTOPILOT_PX4)
}

/// Bytes a client receives within `wait`: `None` when its connection was closed.
async fn heard(client: &mut TcpStream, wait: Duration) -> Option<usize> {
    let mut buf = [0u8; 1024];
    match timeout(wait, client.read(&mut buf)).await {
        Err(_) => Some(0),
        Ok(Ok(0) | Err(_)) => None,
        Ok(Ok(n)) => Some(n),
    }
}

#[tokio::test]
async fn an_idle_and_a_babbling_client_that_came_first_do_not_take_the_link() {
    let t = TcpInTransport::bind("127.0.0.1:0").await.unwrap();
    let port = t.local_addr();
    let mut idle = TcpStream::connect(port).await.unwrap();
    let mut babbler = TcpStream::connect(port).await.unwrap();
    // Garbage and a ground station's heartbeat: not the vehicle.
    babbler.write_all(&[0xfd; 300]).await.unwrap();
    babbler
        .write_all(&heartbeat(77, MavAutopilot::MAV_AUTOPILOT_INVALID))
        .await
        .unwrap();
    let mut vehicle = TcpStream::connect(port).await.unwrap();
    vehicle.write_all(&vehicle_heartbeat()).await.unwrap();
    let (header, _) = timeout(Duration::from_secs(5), t.recv())
        .await
        .expect("the vehicle is heard")
        .unwrap();
    assert_eq!(header.system_id, 1);
    t.lock(1);
    let msg = MavMessage::HEARTBEAT(HEARTBEAT_DATA::default());
    t.send(MavHeader::default(), &msg).await.unwrap();
    assert!(heard(&mut vehicle, Duration::from_secs(5)).await.is_some_and(|n| n > 0));
    // The other clients are closed and hear nothing.
    assert_eq!(heard(&mut idle, Duration::from_secs(5)).await, None);
    babbler.write_all(&vehicle_heartbeat()).await.ok();
    assert_eq!(heard(&mut babbler, Duration::from_secs(5)).await, None);
}

#[tokio::test]
async fn more_idle_clients_than_places_cannot_keep_the_vehicle_out() {
    let t = TcpInTransport::bind("127.0.0.1:0").await.unwrap();
    let port = t.local_addr();
    let mut idle = Vec::new();
    for _ in 0..3 * MAX_UNDECIDED {
        idle.push(TcpStream::connect(port).await.unwrap());
    }
    let mut vehicle = TcpStream::connect(port).await.unwrap();
    vehicle.write_all(&vehicle_heartbeat()).await.unwrap();
    let (header, _) = timeout(Duration::from_secs(5), t.recv())
        .await
        .expect("the vehicle is heard")
        .unwrap();
    assert_eq!(header.system_id, 1);
}

#[tokio::test]
async fn without_a_client_nothing_blocks_and_a_vehicle_that_leaves_is_told() {
    let t = TcpInTransport::bind("127.0.0.1:0").await.unwrap();
    // Binding returned: the wait for a vehicle is the caller's, bounded as it chooses.
    assert!(timeout(Duration::from_millis(200), t.recv()).await.is_err());
    let mut vehicle = TcpStream::connect(t.local_addr()).await.unwrap();
    vehicle.write_all(&vehicle_heartbeat()).await.unwrap();
    assert!(timeout(Duration::from_secs(5), t.recv()).await.unwrap().is_ok());
    drop(vehicle);
    let ended = timeout(Duration::from_secs(5), t.recv())
        .await
        .expect("told")
        .unwrap_err();
    assert!(ended.to_string().contains("TCP connection ended"), "{ended}");
}
