//! A small rust-mavlink GCS used by the tests: every wait is bounded.

use std::net::UdpSocket;
use std::sync::Arc;
use std::time::Duration;

use mavlink::dialects::common::*;
use mavlink::{AsyncConnectable, AsyncConnection, AsyncMavConnection, MavHeader, UdpConfig, UdpMode};
use mock_autopilot::{Builder, LinkSpec, MockAutopilot, MockHandle, SpeedFactor};

pub const GCS: MavHeader = MavHeader {
    system_id: 255,
    component_id: 190,
    sequence: 0,
};

pub struct Gcs {
    pub conn: Arc<AsyncConnection<MavMessage>>,
}

/// A mock on 127.0.0.1:0 (udpin side) with `speed`, configured by `f`.
pub async fn mock(speed: f64, f: impl FnOnce(Builder) -> Builder) -> MockHandle {
    f(MockAutopilot::builder()
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(SpeedFactor::Times(speed)))
    .spawn()
    .await
    .expect("mock starts")
}

impl Gcs {
    pub async fn connect(mock: &MockHandle) -> Gcs {
        let addr = mock.local_addr().expect("udp mock has an address");
        let sock = UdpSocket::bind("127.0.0.1:0").expect("bind");
        sock.connect(addr).expect("connect");
        let conn = UdpConfig::from_socket(sock, UdpMode::Udpout)
            .expect("config")
            .connect_async::<MavMessage>()
            .await
            .expect("open");
        Gcs { conn: Arc::new(conn) }
    }

    pub async fn send(&self, m: &MavMessage) {
        self.conn.send(&GCS, m).await.expect("send");
    }

    /// Wait up to `timeout` (wall) for a message `pick` accepts.
    pub async fn wait<T>(&self, timeout: Duration, mut pick: impl FnMut(&MavMessage) -> Option<T>) -> Option<T> {
        tokio::time::timeout(timeout, async {
            loop {
                if let Ok((_, m)) = self.conn.recv().await
                    && let Some(t) = pick(&m)
                {
                    return t;
                }
            }
        })
        .await
        .ok()
    }

    /// Wait (bounded) for SYS_STATUS's pre-arm bit, as a client of PX4 must before starting: the estimator
    /// settles after boot. True when it came.
    pub async fn wait_prearm(&self, timeout: Duration) -> bool {
        self.wait(timeout, |msg| match msg {
            MavMessage::SYS_STATUS(s)
                if s.onboard_control_sensors_health
                    .contains(MavSysStatusSensor::MAV_SYS_STATUS_PREARM_CHECK) =>
            {
                Some(())
            }
            _ => None,
        })
        .await
        .is_some()
    }

    /// Send `m` and wait for a reply, resending every 200 ms, at most `tries` times.
    pub async fn request<T>(
        &self,
        m: &MavMessage,
        tries: u32,
        mut pick: impl FnMut(&MavMessage) -> Option<T>,
    ) -> Option<T> {
        for _ in 0..tries {
            self.send(m).await;
            if let Some(t) = self.wait(Duration::from_millis(200), &mut pick).await {
                return Some(t);
            }
        }
        None
    }

    /// Upload `items` of `ty` over a lossy link; returns the final MISSION_ACK code.
    pub async fn upload(&self, ty: MavMissionType, items: &[MISSION_ITEM_INT_DATA]) -> Option<MavMissionResult> {
        let count = MavMessage::MISSION_COUNT(MISSION_COUNT_DATA {
            count: items.len() as u16,
            target_system: 1,
            target_component: 1,
            mission_type: ty,
            opaque_id: 0,
        });
        self.send(&count).await;
        let mut last: Option<MavMessage> = None;
        for _ in 0..100 {
            let got = self
                .wait(Duration::from_millis(300), |m| match m {
                    MavMessage::MISSION_REQUEST_INT(r) if r.mission_type == ty => Some(Err(r.seq)),
                    MavMessage::MISSION_ACK(a) if a.mission_type == ty => Some(Ok(a.mavtype)),
                    _ => None,
                })
                .await;
            match got {
                Some(Ok(code)) => return Some(code),
                Some(Err(seq)) => {
                    if let Some(it) = items.get(usize::from(seq)) {
                        let mut it = it.clone();
                        it.mission_type = ty;
                        let m = MavMessage::MISSION_ITEM_INT(it);
                        self.send(&m).await;
                        last = Some(m);
                    }
                }
                // Lost COUNT or lost ACK: repeat what we sent last.
                None => self.send(last.as_ref().unwrap_or(&count)).await,
            }
        }
        None
    }

    pub async fn command(&self, cmd: MavCmd, p: [f32; 7]) -> Option<MavResult> {
        let m = mock_autopilot::scenarios::command(cmd, p);
        self.request(&m, 10, |r| match r {
            MavMessage::COMMAND_ACK(a) if a.command == cmd => Some(a.result),
            _ => None,
        })
        .await
    }
}
