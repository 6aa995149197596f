//! Mission 2 (takeoff, one waypoint, land; 10 m) flown to landing and disarm.
//!
//! `in_process`: the sans-IO vehicle stepped as fast as possible (4 ms physics step).
//! `udp_*`: the full stack, a rust-mavlink client on an ephemeral UDP port uploading, starting
//! and waiting for the disarm, at speed factor 200. (Unpaced, "max", the mission protocol's timers run out
//! before this simple, non-retrying client answers, so that mode is for in-process use.)

use std::net::UdpSocket;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use mavlink::dialects::common::*;
use mavlink::{AsyncConnectable, AsyncMavConnection, MavHeader, UdpConfig, UdpMode};
use mock_autopilot::scenarios::{case_study_params, command, fly_until_disarmed, mission2, upload};
use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor, Vehicle, VehicleConfig};

const GCS: MavHeader = MavHeader {
    system_id: 255,
    component_id: 190,
    sequence: 0,
};

fn in_process() -> Duration {
    let mut v = Vehicle::new(VehicleConfig {
        params: case_study_params(),
        ..Default::default()
    });
    upload(&mut v, MavMissionType::MAV_MISSION_TYPE_MISSION, &mission2());
    fly_until_disarmed(&mut v, Duration::from_millis(4), Duration::from_secs(300), |_, _| {}).expect("lands")
}

async fn over_udp(speed: SpeedFactor) {
    let mut b = MockAutopilot::builder()
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(speed);
    for (n, v) in case_study_params() {
        b = b.param(&n, v);
    }
    let mock = b.spawn().await.expect("mock");
    let sock = UdpSocket::bind("127.0.0.1:0").expect("bind");
    sock.connect(mock.local_addr().expect("addr")).expect("connect");
    let conn = UdpConfig::from_socket(sock, UdpMode::Udpout)
        .expect("cfg")
        .connect_async::<MavMessage>()
        .await
        .expect("open");
    let items = mission2();
    let count = MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
        count: items.len() as u16,
        target_system: 1,
        target_component: 1,
        ..Default::default()
    });
    conn.send(&GCS, &count).await.expect("send");
    let done = tokio::time::timeout(Duration::from_secs(10), async {
        let mut started = false;
        let mut armed = false;
        loop {
            let Ok((_, m)) = conn.recv().await else { continue };
            match m {
                MavMessage::MISSION_REQUEST_INT(r) => {
                    if let Some(it) = items.get(usize::from(r.seq)) {
                        conn.send(&GCS, &MavMessage::MISSION_ITEM_INT(it.clone()))
                            .await
                            .expect("send");
                    }
                }
                MavMessage::MISSION_ACK(_) if !started => {
                    started = true;
                    conn.send(&GCS, &command(MavCmd::MAV_CMD_MISSION_START, [0.0; 7]))
                        .await
                        .expect("send");
                }
                MavMessage::HEARTBEAT(h) => {
                    let a = h.base_mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED);
                    armed |= a;
                    if armed && !a {
                        return;
                    }
                }
                _ => {}
            }
        }
    })
    .await;
    assert!(done.is_ok(), "mission 2 did not finish");
    mock.shutdown().await.expect("stop");
}

fn bench(c: &mut Criterion) {
    let sim = in_process();
    eprintln!("mission 2: {:.1} s simulated to disarm", sim.as_secs_f64());
    let rt = tokio::runtime::Runtime::new().expect("runtime");
    let mut g = c.benchmark_group("mission2_to_landing");
    g.sample_size(10);
    g.bench_function("in_process", |b| b.iter(in_process));
    g.bench_function("udp_speed_factor_200", |b| {
        b.iter(|| rt.block_on(over_udp(SpeedFactor::Times(200.0))))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
