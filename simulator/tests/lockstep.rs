//! The lockstep link against a fake PX4 on a loopback TCP client: freewheel before the first motor
//! command, one step per answer after it, HIL_STATE_QUATERNION only once asked for, the gate holding
//! simulated time, and a closed connection reported as a lost link.

use std::time::Duration;

use mavlink::dialects::common::MavMessage;
use mavlink::{AsyncMavlinkReader, MavHeader};
use simulator::hil::gate::{GateConfig, gate};
use simulator::hil::lockstep::LockstepConfig;
use simulator::hil::messages::{actuator_controls, set_message_interval};
use simulator::hil::tcp::SitlServer;
use simulator::{Cancel, SimConfig, SimError, SimTime, Simulator};
use tokio::net::TcpStream;
use tokio::net::tcp::OwnedReadHalf;

type Reader = AsyncMavlinkReader<OwnedReadHalf>;

async fn next(reader: &mut Reader, within: Duration) -> Option<MavMessage> {
    match tokio::time::timeout(within, reader.read_any_message::<MavMessage>()).await {
        Ok(Ok((_, m))) => Some(m),
        _ => None,
    }
}

/// The next HIL_SENSOR's time_usec, skipping other messages.
async fn next_sensor(reader: &mut Reader, within: Duration) -> Option<u64> {
    let deadline = tokio::time::Instant::now() + within;
    loop {
        let left = deadline.saturating_duration_since(tokio::time::Instant::now());
        match next(reader, left).await? {
            MavMessage::HIL_SENSOR(s) => return Some(s.time_usec),
            _ => continue,
        }
    }
}

async fn send(w: &mut tokio::net::tcp::OwnedWriteHalf, m: &MavMessage) {
    let header = MavHeader {
        system_id: 1,
        component_id: 1,
        sequence: 0,
    };
    mavlink::write_v2_msg_async(w, header, m).await.expect("send");
}

#[tokio::test]
async fn a_fake_px4_sees_freewheel_then_lockstep_then_a_lost_link() {
    let server = SitlServer::bind("127.0.0.1:0".parse().expect("addr"))
        .await
        .expect("bind");
    let addr = server.local_addr();
    let (g, mut holds) = gate(GateConfig {
        period: Some(Duration::from_millis(100)),
        max_hold: Duration::from_secs(2),
    });
    let mut sim = Simulator::new(SimConfig::default()).with_gate(g);
    let clock = sim.clock();
    let cancel = Cancel::new();
    let config = LockstepConfig {
        actuator_wait: Duration::from_millis(500),
        link_lost_after: Duration::from_secs(3),
        freewheel_speed: 1.0,
        ..LockstepConfig::default()
    };
    let run = tokio::spawn(async move {
        sim.run_sitl(&server, Duration::from_secs(10), &config, &Cancel::new())
            .await
    });
    let host = tokio::spawn(async move {
        let mut at = Vec::new();
        while let Some(h) = holds.next_hold().await {
            at.push(h.at);
        }
        at
    });

    let (read, mut write) = TcpStream::connect(addr).await.expect("connect").into_split();
    let mut reader = AsyncMavlinkReader::new(read);
    // Freewheel: sensor time moves by itself, 4 ms a step, starting at 4 ms.
    let first = next_sensor(&mut reader, Duration::from_secs(2))
        .await
        .expect("a sensor message");
    assert_eq!(first, 4000);
    let mut t = first;
    for _ in 0..20 {
        let n = next_sensor(&mut reader, Duration::from_secs(2))
            .await
            .expect("freewheel");
        assert_eq!(n, t + 4000);
        t = n;
    }
    send(&mut write, &set_message_interval(115, 4000.0)).await;
    // Lockstep: each answer buys exactly one step; without one, nothing comes before the wait runs out.
    send(&mut write, &actuator_controls(t, &[0.0; 4], false)).await;
    let mut saw_state = false;
    for _ in 0..200 {
        // Drain what the freewheel already sent, answering each sensor message.
        let deadline = tokio::time::Instant::now() + Duration::from_secs(2);
        loop {
            let left = deadline.saturating_duration_since(tokio::time::Instant::now());
            match next(&mut reader, left).await.expect("a message") {
                MavMessage::HIL_SENSOR(s) => {
                    t = s.time_usec;
                    break;
                }
                MavMessage::HIL_STATE_QUATERNION(_) => saw_state = true,
                _ => {}
            }
        }
        send(&mut write, &actuator_controls(t, &[0.0; 4], false)).await;
    }
    assert!(saw_state, "HIL_STATE_QUATERNION once asked for");
    // Unanswered, at most the few steps already in flight arrive at once; the next waits for the bound.
    let last_answer = tokio::time::Instant::now();
    let mut early = 0;
    let mut after_bound = None;
    while let Some(m) = next(&mut reader, Duration::from_millis(900)).await {
        if let MavMessage::HIL_SENSOR(_) = m {
            let since = last_answer.elapsed();
            if since >= Duration::from_millis(300) {
                after_bound = Some(since);
                break;
            }
            early += 1;
        }
    }
    assert!(early <= 3, "{early} steps without an answer");
    let waited = after_bound.expect("a step after the bound");
    assert!(waited < Duration::from_millis(800), "{waited:?}");
    assert!(clock.now() >= SimTime::from_micros(t));
    // PX4 goes away: the run ends with a lost link, never hangs.
    drop(write);
    drop(reader);
    let result = tokio::time::timeout(Duration::from_secs(5), run)
        .await
        .expect("ends")
        .expect("joined");
    assert!(matches!(result, Err(SimError::LinkLost(_))), "{result:?}");
    let held = host.await.expect("host");
    assert!(
        !held.is_empty()
            && held
                .iter()
                .enumerate()
                .all(|(i, h)| *h == SimTime::from_millis(100 * (i as u64 + 1))),
        "{held:?}"
    );
    cancel.cancel();
}

#[tokio::test]
async fn a_taken_port_is_named_with_the_fix() {
    let first = SitlServer::bind("127.0.0.1:0".parse().expect("addr"))
        .await
        .expect("bind");
    let err = SitlServer::bind(first.local_addr()).await.expect_err("taken");
    let text = err.to_string();
    assert!(
        text.contains(&first.local_addr().port().to_string()) && text.contains("in use"),
        "{text}"
    );
}

#[tokio::test]
async fn no_px4_connecting_ends_with_a_clear_error() {
    let mut sim = Simulator::new(SimConfig::default());
    let server = SitlServer::bind("127.0.0.1:0".parse().expect("addr"))
        .await
        .expect("bind");
    let r = sim
        .run_sitl(
            &server,
            Duration::from_millis(100),
            &LockstepConfig::default(),
            &Cancel::new(),
        )
        .await;
    assert!(matches!(r, Err(SimError::NoConnection { .. })), "{r:?}");
}
