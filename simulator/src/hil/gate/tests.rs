//! The gate without a simulator: holds at its instants, releases, late releases.

use std::time::Duration;

use nalgebra::{UnitQuaternion, Vector3};

use super::*;

fn truth_at(ms: u64) -> GroundTruth {
    GroundTruth {
        time: SimTime::from_millis(ms),
        position_ned_m: Vector3::zeros(),
        position: geodesy::SIM_HOME,
        velocity_ned_m_s: Vector3::zeros(),
        attitude: UnitQuaternion::identity(),
        rates_frd_rad_s: Vector3::zeros(),
        specific_force_frd_m_s2: Vector3::zeros(),
        on_ground: true,
        armed: false,
    }
}

fn periodic(ms: u64, max_hold_ms: u64) -> (Gate, GateHandle) {
    gate(GateConfig {
        period: Some(Duration::from_millis(ms)),
        max_hold: Duration::from_millis(max_hold_ms),
    })
}

#[tokio::test]
async fn it_holds_every_period_until_released() {
    let (mut g, mut h) = periodic(100, 2000);
    let host = tokio::spawn(async move {
        let mut seen = Vec::new();
        while let Some(hold) = h.next_hold().await {
            seen.push((hold.at, hold.truth.time));
            hold.release();
        }
        seen
    });
    let mut passages = Vec::new();
    for k in 1..=60 {
        passages.push(g.pass(&truth_at(k * 4)).await);
    }
    drop(g);
    let seen = host.await.expect("host");
    // 100 ms and 200 ms were passed at the first step ends at or after them: 100 and 200 ms.
    assert_eq!(
        seen,
        vec![
            (SimTime::from_millis(100), SimTime::from_millis(100)),
            (SimTime::from_millis(200), SimTime::from_millis(200))
        ]
    );
    assert_eq!(passages.iter().filter(|p| **p == Passage::Released).count(), 2);
}

#[tokio::test]
async fn registered_instants_hold_once_each() {
    let (mut g, mut h) = gate(GateConfig::default());
    h.hold_at(SimTime::from_millis(10));
    h.hold_at(SimTime::from_millis(11));
    h.hold_at(SimTime::from_millis(30));
    let host = tokio::spawn(async move {
        let mut at = Vec::new();
        while let Some(hold) = h.next_hold().await {
            at.push(hold.at.as_micros() / 1000);
            // Dropping the hold releases it.
        }
        at
    });
    for k in 1..=10 {
        g.pass(&truth_at(k * 4)).await;
    }
    drop(g);
    // 10 and 11 ms both fall in the step ending at 12 ms: one hold.
    assert_eq!(host.await.expect("host"), vec![10, 30]);
}

#[tokio::test]
async fn a_late_release_lets_the_simulator_go_on_and_is_counted() {
    let (mut g, mut h) = periodic(4, 20);
    let host = tokio::spawn(async move {
        let hold = h.next_hold().await.expect("a hold");
        tokio::time::sleep(Duration::from_millis(200)).await;
        drop(hold);
        h
    });
    let start = std::time::Instant::now();
    assert_eq!(g.pass(&truth_at(4)).await, Passage::Late);
    assert!(start.elapsed() < Duration::from_millis(150));
    assert_eq!(g.counts(), (1, 1));
    let h = host.await.expect("host");
    assert_eq!(h.late_releases(), 1);
}

#[tokio::test]
async fn without_a_handle_the_gate_never_holds() {
    let (mut g, h) = periodic(4, 1000);
    drop(h);
    assert_eq!(g.pass(&truth_at(4)).await, Passage::Open);
}
