//! Tests of the waypoint generator: path-following known answers (docs/planner.md §15), states and the speed rules.

use super::*;
use crate::params::PlannerParams;

fn path_nodes() -> Vec<Vector3<f32>> {
    // AV getSetpointFromPath: 1 m segments n0 (root) .. n4, returned deepest first.
    let n0 = Vector3::new(0.0f32, 0.0, 2.5);
    let n1 = Vector3::new(0.8, (1.0f32 - 0.8 * 0.8).sqrt(), 2.5);
    let n2 = Vector3::new(1.5, n1.y + (1.0f32 - 0.7f32.powi(2)).sqrt(), 2.5);
    let n3 = Vector3::new(2.1, n2.y + (1.0f32 - 0.6f32.powi(2)).sqrt(), 2.5);
    let n4 = Vector3::new(2.3, n3.y + (1.0f32 - 0.2f32.powi(2)).sqrt(), 2.5);
    vec![n4, n3, n2, n1, n0]
}

fn between(p: &Vector3<f32>, a: &Vector3<f32>, b: &Vector3<f32>) -> bool {
    (0..3).all(|i| p[i] >= a[i].min(b[i]) - 1e-5 && p[i] <= a[i].max(b[i]) + 1e-5)
}

#[test]
fn known_answer_setpoint_from_path() {
    let path = path_nodes();
    let (n1, n2, n3) = (path[3], path[2], path[1]);
    let now = 100.0;
    let (sp, ok) = setpoint_from_path(&path, Some(now), 1.0, now);
    assert!(ok && between(&sp.unwrap_or_default(), &n1, &n2));
    let (sp, ok) = setpoint_from_path(&path, Some(now - 0.1), 1.0, now);
    assert!(ok && between(&sp.unwrap_or_default(), &n1, &n2));
    let (sp, ok) = setpoint_from_path(&path, Some(now - 1.1), 1.0, now);
    assert!(ok && between(&sp.unwrap_or_default(), &n2, &n3), "{sp:?}");
    assert_eq!(setpoint_from_path(&[], Some(now), 1.0, now), (None, false));
    // Two entries: the non-root node; running off the end: invalid.
    assert_eq!(setpoint_from_path(&path[3..], Some(now), 1.0, now), (Some(n1), true));
    assert!(!setpoint_from_path(&path, Some(now - 3.5), 1.0, now).1);
    assert!(setpoint_from_path(&path, Some(now - 2.5), 1.0, now).1);
}

fn state(p: Vector3<f32>, v: Vector3<f32>, yaw: f32) -> VehicleState {
    VehicleState {
        position_enu: p,
        velocity_enu: v,
        yaw_enu_rad: yaw,
        pitch_rad: 0.0,
    }
}

fn input<'a>(plan: &'a Plan, s: VehicleState, goal: Vector3<f32>) -> WaypointInput<'a> {
    WaypointInput {
        state: s,
        goal_enu: goal,
        prev_goal_enu: goal,
        stay: false,
        is_airborne: true,
        nav_state: NavState::Mission,
        is_land_waypoint: false,
        is_takeoff_waypoint: false,
        desired_vel_enu: None,
        plan,
    }
}

fn generator() -> WaypointGenerator {
    WaypointGenerator::with_fovs(PlannerParams::default().fovs)
}

fn plan_north(t: f64) -> Plan {
    // A straight path North from (0, 0, 5), 2 m edges.
    let path = (0..6).rev().map(|k| Vector3::new(0.0, 2.0 * k as f32, 5.0)).collect();
    Plan {
        path_enu: path,
        path_time_s: Some(t),
        cruise_speed_m_s: 3.0,
        replanned: true,
    }
}

#[test]
fn transition_table() {
    use Transition::*;
    use WaypointState::*;
    assert_eq!(next_state(Loiter, Next1), TryPath);
    assert_eq!(next_state(Loiter, Next2), Loiter);
    assert_eq!(next_state(TryPath, Next1), AltitudeChange);
    assert_eq!(next_state(TryPath, Next2), Direct);
    assert_eq!(next_state(TryPath, Next3), Loiter);
    assert_eq!(next_state(Direct, Next1), TryPath);
    assert_eq!(next_state(Direct, Next2), AltitudeChange);
    assert_eq!(next_state(Direct, Next3), Loiter);
    assert_eq!(next_state(AltitudeChange, Next1), TryPath);
    assert_eq!(next_state(AltitudeChange, Next2), Loiter);
    assert_eq!(next_state(AltitudeChange, Next3), Loiter);
    assert_eq!(next_state(Direct, Repeat), Direct);
}

#[test]
fn loiter_then_direct_without_path_then_try_path_with_one() {
    let mut g = generator();
    let empty = Plan::default();
    let north = std::f32::consts::FRAC_PI_2;
    let s = state(Vector3::new(0.0, 0.0, 5.0), Vector3::zeros(), north);
    let goal = Vector3::new(0.0, 50.0, 5.0);
    assert_eq!(g.state(), WaypointState::Loiter);
    let out = g.step(&input(&empty, s, goal), 0.0);
    assert_eq!(out.goto_enu, s.position_enu, "loiter holds the entry position");
    assert_eq!(g.state(), WaypointState::TryPath);
    g.step(&input(&empty, s, goal), 0.1);
    assert_eq!(g.state(), WaypointState::Direct);
    let out = g.step(&input(&empty, s, goal), 0.2);
    assert!(
        (out.goto_enu - Vector3::new(0.0, 1.0, 5.0)).norm() < 1e-6,
        "direct: unit step at the goal"
    );
    let plan = plan_north(0.25);
    g.step(&input(&plan, s, goal), 0.3);
    assert_eq!(g.state(), WaypointState::TryPath);
    let out = g.step(&input(&plan, s, goal), 0.4);
    assert_eq!(g.state(), WaypointState::TryPath);
    // The carrot is on the path past node 1 (2 m North), so the goto is 1 m North.
    assert!((out.goto_enu - Vector3::new(0.0, 1.0, 5.0)).norm() < 1e-5);
    // Stay -> Loiter.
    let mut stay = input(&plan, s, goal);
    stay.stay = true;
    g.step(&stay, 0.5);
    assert_eq!(g.state(), WaypointState::Loiter);
}

#[test]
fn stale_path_runs_out_then_direct() {
    let mut g = generator();
    let plan = plan_north(0.0); // 10 m path, 8 m after node 1, at 3 m/s valid for ~2.7 s
    let s = state(
        Vector3::new(0.0, 0.0, 5.0),
        Vector3::zeros(),
        std::f32::consts::FRAC_PI_2,
    );
    let goal = Vector3::new(0.0, 50.0, 5.0);
    g.step(&input(&plan, s, goal), 0.0);
    g.step(&input(&plan, s, goal), 1.0);
    assert_eq!(g.state(), WaypointState::TryPath);
    g.step(&input(&plan, s, goal), 2.9);
    assert_eq!(g.state(), WaypointState::Direct);
}

#[test]
fn speed_is_zero_outside_the_fov_and_tapers_inside() {
    let plan = plan_north(0.0);
    let goal = Vector3::new(0.0, 50.0, 5.0);
    let pos = Vector3::new(0.0, 0.0, 5.0);
    for (yaw_deg, expect_moving) in [(90.0f32, true), (-90.0, false)] {
        let mut g = generator();
        let s = state(pos, Vector3::zeros(), yaw_deg.to_radians());
        let mut out = g.step(&input(&plan, s, goal), 0.0);
        for k in 1..20 {
            out = g.step(&input(&plan, s, goal), k as f64 * 0.1);
        }
        let adapted = (out.adapted_goto_enu - pos).norm();
        assert_eq!(adapted > 0.5, expect_moving, "yaw {yaw_deg}: adapted step {adapted}");
        if !expect_moving {
            assert_eq!(adapted, 0.0);
        }
    }
    // Half-way to the FOV edge: the low-passed speed converges to half the cruise speed.
    let mut g = generator();
    let half = PlannerParams::default().fovs[0].h_fov_deg / 4.0;
    let s = state(pos, Vector3::zeros(), (90.0 - half).to_radians());
    let mut out = g.step(&input(&plan, s, goal), 0.0);
    for k in 1..200 {
        out = g.step(&input(&plan, s, goal), k as f64 * 0.1);
    }
    assert!(((out.adapted_goto_enu - pos).norm() - 1.5).abs() < 0.05);
}

#[test]
fn speed_low_pass_time_constant() {
    let mut g = generator();
    let plan = plan_north(0.0);
    let s = state(
        Vector3::new(0.0, 0.0, 5.0),
        Vector3::zeros(),
        std::f32::consts::FRAC_PI_2,
    );
    let goal = Vector3::new(0.0, 50.0, 5.0);
    g.step(&input(&plan, s, goal), 0.0);
    let out = g.step(&input(&plan, s, goal), 0.1);
    // alpha = 0.1 / 1.0; previous speed ~0: speed = 0.1 * 3.
    let step = (out.adapted_goto_enu - s.position_enu).norm();
    assert!((step - 0.3).abs() < 1e-3, "{step}");
}

#[test]
fn near_goal_goto_is_goal_and_heading_is_frozen() {
    let mut g = generator();
    let plan = plan_north(0.0);
    let yaw = 0.3f32;
    let goal = Vector3::new(0.5, 0.5, 5.0);
    let s = state(Vector3::new(0.0, 0.0, 5.0), Vector3::zeros(), yaw);
    g.step(&input(&plan, s, goal), 0.0);
    let out = g.step(&input(&plan, s, goal), 0.1);
    assert_eq!(out.goto_enu, goal);
    assert_eq!(out.yaw_enu_rad, yaw);
    let s2 = state(Vector3::new(0.1, 0.0, 5.0), Vector3::zeros(), 1.0);
    let out = g.step(&input(&plan, s2, goal), 0.2);
    assert_eq!(out.yaw_enu_rad, yaw, "heading stays at the first value inside 1 m");
}

#[test]
fn yaw_smoothing_is_critically_damped_towards_the_goto() {
    let mut g = generator();
    let empty = Plan::default();
    let s = state(Vector3::new(0.0, 0.0, 5.0), Vector3::zeros(), 0.0);
    let goal = Vector3::new(0.0, 50.0, 5.0); // North = +90 deg ENU
    let mut last = 0.0;
    for k in 0..60 {
        let out = g.step(&input(&empty, s, goal), k as f64 * 0.1);
        assert!(out.yaw_enu_rad >= last - 1e-6 && out.yaw_enu_rad <= std::f32::consts::FRAC_PI_2 + 1e-3);
        last = out.yaw_enu_rad;
    }
    assert!((last - std::f32::consts::FRAC_PI_2).abs() < 0.01);
}

#[test]
fn offboard_climbs_first_then_tries_the_path() {
    let mut g = generator();
    let empty = Plan::default();
    let goal = Vector3::new(0.0, 50.0, 5.0);
    let mut inp = input(&empty, state(Vector3::new(0.0, 0.0, 1.0), Vector3::zeros(), 0.0), goal);
    inp.nav_state = NavState::Offboard;
    g.step(&inp, 0.0); // Loiter -> TryPath
    g.step(&inp, 0.1); // TryPath -> AltitudeChange
    assert_eq!(g.state(), WaypointState::AltitudeChange);
    let out = g.step(&inp, 0.2);
    assert_eq!(out.goto_enu, Vector3::new(0.0, 0.0, 2.0), "1 m above");
    inp.state.position_enu.z = 5.0;
    g.step(&inp, 0.3);
    assert_eq!(g.state(), WaypointState::TryPath);
}

#[test]
fn mission_takeoff_and_land_items_change_altitude() {
    let empty = Plan::default();
    let goal = Vector3::new(0.0, 0.0, 5.0);
    for (takeoff, land) in [(true, false), (false, true)] {
        let mut g = generator();
        let mut inp = input(&empty, state(Vector3::new(0.0, 0.0, 1.0), Vector3::zeros(), 0.0), goal);
        inp.is_takeoff_waypoint = takeoff;
        inp.is_land_waypoint = land;
        inp.desired_vel_enu = Some(Vector3::new(0.0, 0.0, 1.0));
        g.step(&inp, 0.0);
        g.step(&inp, 0.1);
        assert_eq!(g.state(), WaypointState::AltitudeChange);
        let out = g.step(&inp, 0.2);
        assert_eq!(out.velocity_enu, [Some(0.0), Some(0.0), Some(1.0)]);
        assert_eq!(out.goto_enu, Vector3::new(0.0, 0.0, 5.0));
    }
    // Moving fast horizontally: brake first.
    let mut g = generator();
    let mut inp = input(
        &empty,
        state(Vector3::new(0.0, 0.0, 1.0), Vector3::new(2.0, 0.0, 0.0), 0.0),
        goal,
    );
    inp.is_takeoff_waypoint = true;
    g.step(&inp, 0.0);
    g.step(&inp, 0.1);
    let out = g.step(&inp, 0.2);
    assert_eq!(out.velocity_enu, [Some(0.0), Some(0.0), None]);
}

#[test]
fn smoothing_converges_to_a_fixed_target() {
    let mut g = generator();
    let plan = plan_north(0.0);
    let s = state(
        Vector3::new(0.0, 0.0, 5.0),
        Vector3::zeros(),
        std::f32::consts::FRAC_PI_2,
    );
    let goal = Vector3::new(0.0, 0.5, 5.0); // within 1 m: goto = goal, speed = 0.5
    let mut out = g.step(&input(&plan, s, goal), 0.0);
    for k in 1..100 {
        out = g.step(&input(&plan, s, goal), k as f64 * 0.1);
    }
    assert!((out.position_enu - goal).norm() < 0.02, "{:?}", out.position_enu);
}
