use std::time::Duration;

use mavlink::dialects::common::{HEARTBEAT_DATA, MavAutopilot, MavModeFlag, MavState, MavType};

use super::*;

fn heartbeat(system_id: u8) -> Vec<u8> {
    let msg = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        custom_mode: 0,
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
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

#[test]
fn the_messages_between_garbage_are_found() {
    let mut datagram = vec![0xfd, 0x09, 0x00, 0xff, 0x13];
    datagram.extend(heartbeat(1));
    datagram.extend([0x00, 0x13, 0x37]);
    datagram.extend(heartbeat(2));
    let found: Vec<u32> = frames(&datagram).iter().map(|(h, _)| h.system_id).collect();
    assert_eq!(found, [1, 2]);
    assert!(frames(&[0xfd; 300]).is_empty());
    assert!(frames(&[]).is_empty());
}

#[tokio::test]
async fn replies_go_to_the_vehicle_whoever_else_floods_the_port() {
    let t = UdpInTransport::bind("127.0.0.1:0").await.unwrap();
    let port = t.local_addr().unwrap();
    let vehicle = tokio::net::UdpSocket::bind("127.0.0.1:0").await.unwrap();
    let flooder = tokio::net::UdpSocket::bind("127.0.0.1:0").await.unwrap();
    vehicle.send_to(&heartbeat(1), port).await.unwrap();
    assert_eq!(t.recv().await.unwrap().0.system_id, 1);
    t.lock(1);
    // Garbage, then another system's valid message, from another address.
    flooder.send_to(&[0xfd; 200], port).await.unwrap();
    flooder.send_to(&heartbeat(77), port).await.unwrap();
    assert_eq!(t.recv().await.unwrap().0.system_id, 77);
    assert_eq!(t.peer(), Some(vehicle.local_addr().unwrap()));
    let header = MavHeader {
        system_id: 245u8.into(),
        component_id: 190,
        sequence: 0,
    };
    t.send(header, &frames(&heartbeat(1))[0].1).await.unwrap();
    let mut buf = [0u8; 512];
    let got = tokio::time::timeout(Duration::from_secs(5), vehicle.recv_from(&mut buf)).await;
    let (n, _) = got.expect("the vehicle hears the reply").unwrap();
    assert_eq!(frames(&buf[..n])[0].0.system_id, 245);
    assert!(flooder.try_recv_from(&mut buf).is_err(), "the flooder got a reply");
}
