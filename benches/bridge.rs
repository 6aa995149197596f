//! Mission upload of 100 items to the mock autopilot on loopback UDP, through the bridge's link and upload
//! state machine: a clean link, and 20 % loss each way (recovered by PX4-style re-requests and our retries).
//! The mock runs in real time (speed factor 1), as PX4 SITL would.

use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use mavlink::dialects::common::{MISSION_ITEM_INT_DATA, MavCmd, MavFrame, MavMissionType};
use mock_autopilot::{Faults, LinkSpec, MockAutopilot, MockHandle, SpeedFactor};
use prgenuav::bridge::CancelToken;
use prgenuav::bridge::wire::clock::VehicleClock;
use prgenuav::bridge::wire::exchange::{RetryPolicy, Target};
use prgenuav::bridge::wire::link::{Link, MavTransport};
use prgenuav::bridge::wire::mission_upload::MissionUpload;

#[expect(deprecated, reason = "PX4 accepts MAV_FRAME_GLOBAL_RELATIVE_ALT_INT")]
fn items(n: usize) -> Vec<MISSION_ITEM_INT_DATA> {
    (0..n)
        .map(|i| MISSION_ITEM_INT_DATA {
            x: 473_977_419 + (i as i32) * 100,
            y: 85_455_938,
            z: 10.0,
            command: MavCmd::MAV_CMD_NAV_WAYPOINT,
            frame: MavFrame::MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            autocontinue: 1,
            ..Default::default()
        })
        .collect()
}

async fn setup(loss: f64) -> (MockHandle, Link) {
    let mock = MockAutopilot::builder()
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(SpeedFactor::Times(1.0))
        .faults(Faults {
            seed: 3,
            loss,
            ..Faults::default()
        })
        .spawn()
        .await
        .expect("mock");
    let port = mock.local_addr().expect("udp").port();
    let t = MavTransport::open(&format!("udpout:127.0.0.1:{port}"))
        .await
        .expect("link");
    let link = Link::new(Arc::new(t), VehicleClock::new(1.0));
    (mock, link)
}

fn upload(c: &mut Criterion) {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    let target = Target {
        system: 1,
        component: 1,
    };
    let plan = items(100);
    let mut group = c.benchmark_group("mission_upload_100");
    group.sample_size(10);
    for (name, loss, secs) in [("loopback", 0.0, 5), ("loss_20pct", 0.2, 60)] {
        let (mock, link) = rt.block_on(setup(loss));
        link.lock(1);
        let cancel = CancelToken::new();
        group.measurement_time(Duration::from_secs(secs));
        group.bench_function(name, |b| {
            b.iter(|| {
                let up = MissionUpload::new(
                    target,
                    MavMissionType::MAV_MISSION_TYPE_MISSION,
                    plan.clone(),
                    RetryPolicy::MISSION,
                );
                rt.block_on(link.exchange(up, &cancel)).expect("upload accepted")
            })
        });
        drop(link);
        rt.block_on(mock.shutdown()).expect("mock stops");
    }
    group.finish();
}

criterion_group!(benches, upload);
criterion_main!(benches);
