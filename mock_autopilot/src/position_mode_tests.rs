use mavlink::dialects::common::{MavDistanceSensor, MavFrame, OBSTACLE_DISTANCE_DATA};

use super::*;
use crate::obstacle_map::{BIN_COUNT, UNKNOWN};
use crate::params::ParamValue;

const DT: f64 = 0.004;

fn table(cp_dist: f32) -> ParamTable {
    let mut t = ParamTable::default();
    t.set("CP_DIST", ParamValue::Float(cp_dist));
    t
}

/// A forward-looking sensor (body frame, +-60 degrees, 20 m range) seeing a wall across North at `wall_x`.
fn wall_reading(body: &Body, wall_x: f64) -> OBSTACLE_DISTANCE_DATA {
    let mut distances = [UNKNOWN; BIN_COUNT];
    for (j, d) in distances.iter_mut().enumerate() {
        let rel = (j as f64 * 5.0 + 180.0).rem_euclid(360.0) - 180.0;
        if rel.abs() > 60.0 {
            continue;
        }
        let c = (body.yaw_rad + rel.to_radians()).cos();
        let range = if c > 1e-6 {
            (wall_x - body.pos_ned.x) / c
        } else {
            f64::INFINITY
        };
        *d = if range < 20.0 {
            (range.max(0.0) * 100.0) as u16
        } else {
            2001
        };
    }
    OBSTACLE_DISTANCE_DATA {
        time_usec: 0,
        distances,
        min_distance: 20,
        max_distance: 2000,
        sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
        increment: 5,
        increment_f: 0.0,
        angle_offset: 0.0,
        frame: MavFrame::MAV_FRAME_BODY_FRD,
    }
}

/// Flies `secs` with sticks `s` from `body`; a wall at `wall_x` is reported at 10 Hz. Returns the mode, the
/// body and the largest North position reached.
fn fly(t: &ParamTable, s: Sticks, mut body: Body, secs: f64, wall_x: Option<f64>) -> (PositionMode, Body, f64) {
    let mp = ManualParams::from_params(t);
    let cpp = CpParams::from_params(t);
    let mut mode = PositionMode::start(&body);
    let mut inbox = RangeInbox::default();
    let mut max_x = f64::MIN;
    let steps = (secs / DT) as u64;
    for k in 0..steps {
        let now = Duration::from_secs(10) + Duration::from_secs_f64(k as f64 * DT);
        if let Some(x) = wall_x
            && k.is_multiple_of(25)
        {
            inbox.put(&wall_reading(&body, x), now);
        }
        let c = mode.step(s, &body, &mp, (&cpp, &inbox, now), DT, &mut Vec::new());
        body.track_manual(&c, &mp, DT, Ned::zeros());
        max_x = max_x.max(body.pos_ned.x);
    }
    (mode, body, max_x)
}

fn hovering() -> Body {
    Body {
        pos_ned: Ned::new(0.0, 0.0, -10.0),
        ..Default::default()
    }
}

fn forward(pitch: f64) -> Sticks {
    Sticks {
        pitch,
        ..Default::default()
    }
}

#[test]
fn full_stick_reaches_mpc_vel_manual_and_release_holds_position() {
    let t = table(-1.0);
    let (_, body, _) = fly(&t, forward(1.0), hovering(), 30.0, None);
    assert!((body.vel_ned.x - 10.0).abs() < 0.3, "{:?}", body.vel_ned);
    assert!(
        (body.pos_ned.z + 10.0).abs() < 0.05,
        "altitude held: {:?}",
        body.pos_ned
    );
    let (_, stopped, _) = fly(&t, Sticks::default(), body, 10.0, None);
    assert!(stopped.vel_ned.norm() < 0.1, "{:?}", stopped.vel_ned);
    let (_, held, _) = fly(&t, Sticks::default(), stopped, 10.0, None);
    assert!(held.vel_ned.norm() < 0.02, "{:?}", held.vel_ned);
    assert!((held.pos_ned - stopped.pos_ned).norm() < 0.3);
}

#[test]
fn half_stick_is_shaped_by_the_expo() {
    // 0.5 out of the 0.1 dead zone with expo 0.6: 0.4 * 0.444 + 0.6 * 0.088 = 0.23 of 10 m/s.
    let (_, body, _) = fly(&table(-1.0), forward(0.5), hovering(), 15.0, None);
    assert!((body.vel_ned.x - 2.3).abs() < 0.15, "{:?}", body.vel_ned);
}

#[test]
fn throttle_climbs_and_yaw_stick_turns() {
    let s = Sticks {
        throttle: 1.0,
        yaw: 1.0,
        ..Default::default()
    };
    let (_, body, _) = fly(&table(-1.0), s, hovering(), 4.0, None);
    assert!((body.vel_ned.z + 3.0).abs() < 0.1, "{:?}", body.vel_ned);
    assert!((body.yaw_rate_rad_s - 150f64.to_radians()).abs() < 1e-9);
}

#[test]
fn collision_prevention_stops_before_a_wall_and_cp_dist_minus_one_flies_into_it() {
    let (_, body, max_x) = fly(&table(4.0), forward(1.0), hovering(), 25.0, Some(30.0));
    let gap = 30.0 - max_x;
    assert!(gap > 3.0 && gap < 5.0, "closest {gap} m from the wall, CP_DIST 4");
    assert!(body.vel_ned.xy().norm() < 0.3);
    let (_, _, max_x) = fly(&table(-1.0), forward(1.0), hovering(), 25.0, Some(30.0));
    assert!(max_x > 30.0, "without Collision Prevention it flies through: {max_x}");
}

#[test]
fn landed_without_throttle_nothing_moves() {
    let (_, body, _) = fly(&table(-1.0), forward(1.0), Body::default(), 2.0, None);
    assert_eq!(body.pos_ned, Ned::zeros());
}
