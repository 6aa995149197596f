use mavlink::dialects::common::{MavDistanceSensor, MavFrame};

use super::*;
use crate::obstacle_map::BIN_COUNT;

const T: Duration = Duration::from_secs(20);

fn params(dist_m: f64) -> CpParams {
    let mut t = ParamTable::default();
    t.set("CP_DIST", crate::params::ParamValue::Float(dist_m as f32));
    CpParams::from_params(&t)
}

/// A North-aligned 30 m sensor seeing `ahead_cm` due North within +-`half_deg`, nothing in range elsewhere in
/// its 360-degree view; `blind` sectors (North-aligned, 5 degrees each) unknown. (A reading of "nothing" still
/// scales the stick within `MPC_VEL_MANUAL / MPC_XY_P` beyond CP_DIST, as in PX4, so the range is long.)
fn inbox(ahead_cm: u16, half_deg: f64, blind: &[usize]) -> RangeInbox {
    let mut distances = [3001u16; BIN_COUNT];
    for (j, d) in distances.iter_mut().enumerate() {
        let a = (j as f64 * 5.0 + 180.0).rem_euclid(360.0) - 180.0;
        if a.abs() <= half_deg {
            *d = ahead_cm;
        }
        if blind.contains(&j) {
            *d = UNKNOWN;
        }
    }
    let m = OBSTACLE_DISTANCE_DATA {
        time_usec: 0,
        distances,
        min_distance: 10,
        max_distance: 3000,
        sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
        increment: 5,
        increment_f: 0.0,
        angle_offset: 0.0,
        frame: MavFrame::MAV_FRAME_LOCAL_NED,
    };
    let mut b = RangeInbox::default();
    b.put(&m, T);
    b
}

fn run(cp: &mut CollisionPrevention, acc: Xy, vel: Xy, b: &RangeInbox, p: &CpParams) -> (Xy, Vec<CpEvent>) {
    let mut ev = Vec::new();
    assert!(cp.active(p, T));
    let out = cp.modify(acc, vel, 0.0, (b, T), p, &mut ev);
    (out, ev)
}

#[test]
fn far_obstacles_leave_the_stick_alone() {
    let p = params(2.0);
    let (out, ev) = run(
        &mut CollisionPrevention::default(),
        Xy::new(6.0, 0.0),
        Xy::zeros(),
        &inbox(3001, 0.0, &[]),
        &p,
    );
    assert!((out - Xy::new(6.0, 0.0)).norm() < 1e-9, "{out}");
    assert!(ev.is_empty());
}

#[test]
fn a_wall_ahead_scales_the_stick_down_and_brakes_a_fast_setpoint() {
    let p = params(2.0);
    let b = inbox(300, 30.0, &[]);
    // 1 m beyond CP_DIST: scale (1 / (10 / 0.95))^2, about 0.009.
    let (out, _) = run(
        &mut CollisionPrevention::default(),
        Xy::new(6.0, 0.0),
        Xy::zeros(),
        &b,
        &p,
    );
    assert!(out.x > 0.0 && out.x < 0.1, "{out}");
    // At 5 m/s towards it the velocity compensation brakes hard.
    let (out, _) = run(
        &mut CollisionPrevention::default(),
        Xy::new(6.0, 0.0),
        Xy::new(5.0, 0.0),
        &b,
        &p,
    );
    assert!(out.x < -5.0, "{out}");
    // Inside CP_DIST the stick pushes back out.
    let (out, _) = run(
        &mut CollisionPrevention::default(),
        Xy::new(6.0, 0.0),
        Xy::zeros(),
        &inbox(150, 30.0, &[]),
        &p,
    );
    assert!(out.x < 0.0, "{out}");
    // Moving away is not constrained.
    let (out, _) = run(
        &mut CollisionPrevention::default(),
        Xy::new(-6.0, 0.0),
        Xy::zeros(),
        &b,
        &p,
    );
    assert!((out - Xy::new(-6.0, 0.0)).norm() < 1e-9, "{out}");
}

#[test]
fn the_guidance_angle_turns_the_setpoint_to_free_space() {
    // A narrow post straight ahead at 4 m, free on both sides: the North stick is turned to the nearest bin with
    // full room on both neighbours (15 degrees, within CP_GUIDE_ANG 30), and only its part towards the post is
    // scaled down: (0.966 * 0.036, 0.259) * 6.
    let p = params(2.0);
    let (out, _) = run(
        &mut CollisionPrevention::default(),
        Xy::new(6.0, 0.0),
        Xy::zeros(),
        &inbox(400, 5.0, &[]),
        &p,
    );
    assert!(
        (out.y.abs() - 1.55).abs() < 0.01 && (out.x - 0.21).abs() < 0.01,
        "{out}"
    );
    let mut q = p;
    q.guide_deg = 0.0;
    let (out, _) = run(
        &mut CollisionPrevention::default(),
        Xy::new(6.0, 0.0),
        Xy::zeros(),
        &inbox(400, 5.0, &[]),
        &q,
    );
    assert!(out.y.abs() < 1e-9, "{out}");
}

#[test]
fn unknown_sectors_block_the_stick_unless_cp_go_no_data() {
    // East (sectors 16..=20) unknown: the East stick is refused with CP_GO_NO_DATA 0 and the guidance
    // cannot reach a known bin (30 degrees of 45 blind).
    let blind: Vec<usize> = (12..=24).collect();
    let b = inbox(3001, 0.0, &blind);
    let p = params(2.0);
    let (out, _) = run(
        &mut CollisionPrevention::default(),
        Xy::new(0.0, 6.0),
        Xy::zeros(),
        &b,
        &p,
    );
    assert_eq!(out, Xy::zeros());
    let mut q = p;
    q.go_no_data = true;
    let (out, _) = run(
        &mut CollisionPrevention::default(),
        Xy::new(0.0, 6.0),
        Xy::zeros(),
        &b,
        &q,
    );
    assert!((out - Xy::new(0.0, 6.0)).norm() < 1e-9, "{out}");
}

#[test]
fn without_data_nothing_moves_and_hold_follows() {
    let p = params(2.0);
    let empty = RangeInbox::default();
    let mut cp = CollisionPrevention::default();
    let mut ev = Vec::new();
    assert!(cp.active(&p, T));
    let mut t = T;
    while t < T + Duration::from_secs(6) {
        assert_eq!(
            cp.modify(Xy::new(6.0, 0.0), Xy::zeros(), 0.0, (&empty, t), &p, &mut ev),
            Xy::zeros()
        );
        if ev.contains(&CpEvent::Hold) {
            break;
        }
        t += Duration::from_millis(100);
    }
    let after = t - T;
    assert!(
        after > NO_DATA_HOLD && after <= NO_DATA_HOLD + Duration::from_millis(1100),
        "{after:?}"
    );
    // Disabled: never active.
    let mut cp = CollisionPrevention::default();
    assert!(!cp.active(&params(-1.0), T));
}
