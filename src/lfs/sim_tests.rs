use std::path::Path;

use super::*;
use crate::model::Obstacle;

fn mission(n: u32) -> TestCase {
    TestCase::load(Path::new(&format!("missions/mission{n}.yaml"))).unwrap()
}

fn two_boxes() -> Vec<Obstacle> {
    vec![
        Obstacle::new(10.0, 5.0, 20.0, 10.0, 20.0, 0.0),
        Obstacle::new(10.0, 5.0, 20.0, -10.0, 20.0, 0.0),
    ]
}

#[test]
fn free_mission_lands_near_the_land_item() {
    for motion in ["paper", "px4"] {
        let config = SimConfig {
            motion: MotionModel::by_name(motion).unwrap(),
            ..Default::default()
        };
        let r = simulate(&mission(1), &config).unwrap();
        assert_eq!(r.status, SimStatus::Landed, "{motion}");
        let last = r.trajectory.samples.last().unwrap();
        assert!(last.z.abs() < 1e-9);
        assert!((last.x - 3.3).hypot(last.y - 53.09) < 1.0, "{motion}: {last:?}");
        let top = r.trajectory.samples.iter().map(|s| s.z).fold(0.0, f64::max);
        assert!((9.0..11.5).contains(&top), "{motion}: cruise altitude {top}");
        assert!(r.distance.is_none());
        assert_eq!(r.cycles as usize + 1, r.trajectory.samples.len());
    }
}

#[test]
fn two_obstacles_are_passed_without_collision() {
    for motion in ["paper", "px4"] {
        let test = mission(2).with_obstacles(two_boxes());
        let config = SimConfig {
            motion: MotionModel::by_name(motion).unwrap(),
            ..Default::default()
        };
        let r = simulate(&test, &config).unwrap();
        assert_eq!(r.status, SimStatus::Landed, "{motion}");
        let d = r.distance.unwrap();
        assert!(
            d.min_distance > 0.3 && d.min_distance < 10.0,
            "{motion}: {}",
            d.min_distance
        );
        assert_eq!(d.per_obstacle.len(), 2);
        assert_eq!(r.full_renders, 0);
    }
}

#[test]
fn termination_statuses() {
    let test = mission(2).with_obstacles(two_boxes());
    let timeout = SimConfig {
        timeout_s: 5.0,
        ..Default::default()
    };
    let r = simulate(&test, &timeout).unwrap();
    assert_eq!(r.status, SimStatus::Timeout);
    assert!((r.flight_time_s - 5.0).abs() < 1e-6 && r.cycles == 50);

    let stuck = SimConfig {
        stuck_s: 3.0,
        progress_m: 1000.0,
        ..Default::default()
    };
    let r = simulate(&test, &stuck).unwrap();
    assert_eq!(r.status, SimStatus::Stuck);
    assert!(r.flight_time_s > 3.0 && r.flight_time_s < 3.5, "{}", r.flight_time_s);

    // Home inside a (low) box: the vehicle is in it from the start.
    let trapped = mission(2).with_obstacles(vec![Obstacle::new(4.0, 4.0, 5.0, 0.0, 0.0, 0.0)]);
    let r = simulate(&trapped, &SimConfig::default()).unwrap();
    assert_eq!(r.status, SimStatus::Collision);
    assert_eq!(r.distance.unwrap().min_distance, 0.0);
}

#[test]
fn stages_are_named_in_order_and_step_is_idempotent_after_the_end() {
    assert_eq!(STAGES, ["sense", "plan", "control", "integrate", "record"]);
    let config = SimConfig {
        timeout_s: 0.3,
        ..Default::default()
    };
    let mut w = World::new(&mission(1), config).unwrap();
    let mut last = None;
    for _ in 0..10 {
        last = step(&mut w, 0.1);
    }
    assert_eq!(last, Some(SimStatus::Timeout));
    assert_eq!(w.cycles, 3);
}

#[test]
fn bad_settings_are_errors() {
    let bad = SimConfig {
        dt_s: 0.0,
        ..Default::default()
    };
    assert!(matches!(World::new(&mission(1), bad), Err(SimError::Setting(_))));
    assert!(MotionModel::by_name("jetpack").is_none());
}

#[test]
fn control_delay_postpones_every_command_by_its_ticks() {
    let first_climb = |delay_ticks: usize| {
        let config = SimConfig {
            motion: MotionModel::Paper(PaperParams {
                delay_ticks,
                ..PaperParams::default()
            }),
            timeout_s: 2.0,
            ..Default::default()
        };
        let r = simulate(&mission(1), &config).unwrap();
        r.trajectory.samples.iter().position(|s| s.z > 0.0).unwrap()
    };
    assert_eq!(first_climb(0), 1, "the takeoff command acts in the first tick");
    assert_eq!(first_climb(3), 4);
    assert_eq!(MotionModel::by_name("paper").unwrap().delay_ticks(), 1);
    assert_eq!(MotionModel::by_name("px4").unwrap().delay_ticks(), 0);
}

#[test]
fn tilted_camera_keeps_the_fast_render_and_passes_the_pitch_on() {
    let test = mission(2).with_obstacles(two_boxes());
    let config = SimConfig {
        tilt: Some(crate::lfs::attitude::TiltParams::default()),
        timeout_s: 30.0,
        ..Default::default()
    };
    let mut w = World::new(&test, config).unwrap();
    let mut max_pitch: f64 = 0.0;
    while step(&mut w, 0.1).is_none() {
        max_pitch = max_pitch.max(f64::from(w.vehicle_state().pitch_rad));
    }
    // The vehicle accelerates forward at the start of the cruise, so it pitched nose-down at some point.
    assert!(max_pitch > 1f64.to_radians(), "{}", max_pitch.to_degrees());
    assert_eq!(w.full_renders(), 0);
}

#[test]
fn estimated_fov_is_narrow_and_low_after_a_ground_only_takeoff() {
    let config = SimConfig {
        motion: MotionModel::by_name("px4").unwrap(),
        planner: prgenuav_planner::PlannerParams {
            fov_estimate: prgenuav_planner::fov_estimate::FovEstimate::FromMaxima,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut w = World::new(&mission(1), config).unwrap();
    while w.mission().phase() != crate::lfs::mission::Phase::Cruise {
        assert!(step(&mut w, 0.1).is_none());
    }
    let f = w.planner().fovs()[0];
    assert!((f.h_fov_deg - 58.9).abs() < 0.3, "{f:?}");
    assert!(f.v_fov_deg < 25.0 && f.pitch_deg > 8.0, "{f:?}");
    let r = simulate(&mission(1), w.config()).unwrap();
    assert_eq!(r.status, SimStatus::Landed);
}
