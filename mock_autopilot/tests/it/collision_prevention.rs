//! Position mode and Collision Prevention over UDP: a client streams MANUAL_CONTROL sticks and OBSTACLE_DISTANCE
//! scans of a box, as a pilot with a range sensor would.

use std::time::Duration;

use mavlink::AsyncMavConnection;
use mavlink::dialects::common::*;
use mock_autopilot::obstacles::{ObstacleWorld, SolidBox};
use mock_autopilot::range_scan::RangeSensor;
use mock_autopilot::release::Px4Release;
use mock_autopilot::{FlightMode, MockHandle};

use crate::client::{Gcs, mock};

/// Vehicle seconds per wall second: slow enough that 10 ms of client pacing is 40 ms of vehicle time.
const SPEED: f64 = 4.0;

/// A box across North, near face at x = 15 m, 30 m wide, 20 m high.
fn wall() -> SolidBox {
    SolidBox {
        x: 16.0,
        y: 0.0,
        l: 2.0,
        w: 30.0,
        r_deg: 0.0,
        bottom_m: 0.0,
        top_m: 20.0,
    }
}

/// A mock acting as PX4 v1.16.2, whose Collision Prevention (at the default `MPC_POS_MODE` 4) it models.
async fn spawn() -> MockHandle {
    mock(SPEED, |b| {
        b.collision(Box::new(ObstacleWorld::new(vec![wall()])))
            .estimator_settle(Duration::ZERO)
            .px4_release(v1_16())
    })
    .await
}

fn v1_16() -> Px4Release {
    Px4Release::parse("1.16.2").expect("a release")
}

fn sticks(x: i16) -> MavMessage {
    MavMessage::MANUAL_CONTROL(MANUAL_CONTROL_DATA {
        x,
        z: 500,
        target: 1,
        ..Default::default()
    })
}

async fn set_param(gcs: &Gcs, name: &str, value: f32) {
    let m = MavMessage::PARAM_SET(PARAM_SET_DATA {
        param_value: value,
        target_system: 1,
        target_component: 1,
        param_id: name.into(),
        param_type: MavParamType::MAV_PARAM_TYPE_REAL32,
    });
    let echoed = gcs
        .request(&m, 10, |r| match r {
            MavMessage::PARAM_VALUE(p) if p.param_id.to_str().ok() == Some(name) => Some(p.param_value),
            _ => None,
        })
        .await;
    assert_eq!(echoed, Some(value), "{name} set");
}

/// What a stick flight saw.
#[derive(Default)]
struct Flight {
    max_x: f64,
    echoes: usize,
}

/// Streams `x` sticks (and scans of the wall when `sensor`) for `secs` of vehicle time.
async fn fly_sticks(m: &MockHandle, gcs: &Gcs, secs: f64, x: i16, sensor: Option<RangeSensor>) -> Flight {
    let mut f = Flight::default();
    let mut yaw = 0.0f64;
    let mut tick = tokio::time::interval(Duration::from_millis(10));
    let deadline = tokio::time::Instant::now() + Duration::from_secs_f64(secs / SPEED);
    while tokio::time::Instant::now() < deadline {
        tokio::select! {
            _ = tick.tick() => {
                gcs.send(&sticks(x)).await;
                if let Some(s) = sensor {
                    gcs.send(&MavMessage::OBSTACLE_DISTANCE(s.scan(&[wall()], &m.state().pos_ned, yaw, 0))).await;
                }
                f.max_x = f.max_x.max(m.state().pos_ned.x);
            }
            got = gcs.conn.recv() => match got {
                Ok((_, MavMessage::ATTITUDE(a))) => yaw = f64::from(a.yaw),
                Ok((_, MavMessage::OBSTACLE_DISTANCE(o))) if o.frame == MavFrame::MAV_FRAME_BODY_FRD => f.echoes += 1,
                _ => {}
            },
        }
    }
    f
}

/// Armed, taken off and in Position mode (sticks centred first, as PX4 requires).
async fn airborne_in_posctl(m: &MockHandle, gcs: &Gcs, sensor: Option<RangeSensor>) {
    let arm = gcs.command(
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    assert_eq!(arm.await, Some(MavResult::MAV_RESULT_ACCEPTED));
    let takeoff = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, f32::NAN];
    assert_eq!(
        gcs.command(MavCmd::MAV_CMD_NAV_TAKEOFF, takeoff).await,
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    fly_sticks(m, gcs, 7.0, 0, sensor).await;
    let posctl = [1.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert_eq!(
        gcs.command(MavCmd::MAV_CMD_DO_SET_MODE, posctl).await,
        Some(MavResult::MAV_RESULT_ACCEPTED)
    );
    assert_eq!(m.state().mode, FlightMode::Posctl);
    assert!(m.state().pos_ned.z < -2.0, "airborne: {:?}", m.state().pos_ned);
}

fn sensor() -> Option<RangeSensor> {
    Some(RangeSensor {
        fov_deg: 90.0,
        min_m: 0.2,
        max_m: 25.0,
    })
}

#[tokio::test]
async fn sticks_towards_a_box_stop_near_cp_dist() {
    let m = spawn().await;
    let gcs = Gcs::connect(&m).await;
    set_param(&gcs, "CP_DIST", 3.0).await;
    airborne_in_posctl(&m, &gcs, sensor()).await;
    let f = fly_sticks(&m, &gcs, 16.0, 1000, sensor()).await;
    let gap = 15.0 - f.max_x;
    assert!(gap > 2.0 && gap < 3.5, "closest {gap:.2} m from the box with CP_DIST 3");
    assert!(!m.state().crashed);
    assert!(f.echoes >= 50, "the fused map comes back at 10 Hz: {}", f.echoes);
    m.shutdown().await.expect("shutdown");
}

#[tokio::test]
async fn without_range_data_the_sticks_move_nothing() {
    let m = spawn().await;
    let gcs = Gcs::connect(&m).await;
    set_param(&gcs, "CP_DIST", 3.0).await;
    airborne_in_posctl(&m, &gcs, None).await;
    let start = m.state().pos_ned;
    let f = fly_sticks(&m, &gcs, 3.0, 1000, None).await;
    assert!(f.max_x - start.x < 0.2, "moved {:.2} m", f.max_x - start.x);
    m.shutdown().await.expect("shutdown");
}

#[tokio::test]
async fn cp_dist_minus_one_flies_into_the_box() {
    let m = spawn().await;
    let gcs = Gcs::connect(&m).await;
    airborne_in_posctl(&m, &gcs, sensor()).await;
    let f = fly_sticks(&m, &gcs, 10.0, 1000, sensor()).await;
    assert!(m.state().crashed, "reached x {:.1}", f.max_x);
    m.shutdown().await.expect("shutdown");
}
