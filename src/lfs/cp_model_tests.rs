use super::*;
use crate::model::Obstacle;

fn mission2() -> TestCase {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
    TestCase::load(&path).unwrap()
}

/// The leg's midpoint and its unit direction (North, East) between waypoints 1 and 2 of mission 2.
fn leg(test: &TestCase) -> ([f64; 2], [f64; 2]) {
    let w = waypoints(&test.mission);
    let (a, b) = (w[0], w[1]);
    let d = [b[0] - a[0], b[1] - a[1]];
    let n = d[0].hypot(d[1]);
    ([(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0], [d[0] / n, d[1] / n])
}

#[test]
fn without_boxes_the_pilot_flies_the_mission_and_lands() {
    let mut t = mission2();
    t.obstacles.clear();
    let p = simulate_cp(&t, &CpParams::default(), &CpSimConfig::default());
    assert_eq!(p.end, CpEnd::Landed);
    assert_eq!(p.min_distance, None);
    let last = p.trajectory.samples.last().unwrap();
    let goal = *waypoints(&t.mission).last().unwrap();
    // The sticks are centred slowly before LAND (PX4 takes a fast centring as a takeover): it drifts on.
    assert!(
        (last.x - goal[0]).hypot(last.y - goal[1]) < 5.0 && last.z.abs() < 1e-9,
        "{last:?}"
    );
}

#[test]
fn a_wall_across_the_path_holds_the_vehicle_near_cp_dist() {
    let mut t = mission2();
    let (mid, dir) = leg(&t);
    // A 2 m deep wall, 30 m wide, across the leg.
    let r = dir[1].atan2(dir[0]).to_degrees();
    t.obstacles = vec![Obstacle::new(2.0, 30.0, 20.0, mid[0], mid[1], r)];
    let p = simulate_cp(&t, &CpParams::default(), &CpSimConfig::default());
    assert!(matches!(p.end, CpEnd::Stuck(_)), "{:?}", p.end);
    let d = p.min_distance.unwrap();
    assert!(d > 1.0 && d < 2.5, "held near CP_DIST 2 m: {d}");
    // A larger CP_DIST holds it farther away.
    let far = CpParams {
        dist_m: 4.0,
        ..CpParams::default()
    };
    let d4 = simulate_cp(&t, &far, &CpSimConfig::default()).min_distance.unwrap();
    assert!(d4 > d + 1.0, "{d4} vs {d}");
}

#[test]
fn a_box_beside_the_path_is_passed() {
    let mut t = mission2();
    let (mid, dir) = leg(&t);
    // On the side away from the return leg (mission 2 flies out and back).
    let side = [dir[1], -dir[0]];
    // A 2 m box whose near face is 4 m beside the leg.
    let c = [mid[0] + side[0] * 5.0, mid[1] + side[1] * 5.0];
    t.obstacles = vec![Obstacle::new(2.0, 2.0, 20.0, c[0], c[1], 0.0)];
    let p = simulate_cp(&t, &CpParams::default(), &CpSimConfig::default());
    assert_eq!(p.end, CpEnd::Landed);
    let d = p.min_distance.unwrap();
    assert!(d > 2.5 && d < 4.5, "{d}");
}

#[test]
fn the_throttle_maps_to_climb_rates_with_a_dead_zone() {
    let c = CpSimConfig::default();
    assert_eq!(climb_rate(0.5, &c), 0.0);
    assert_eq!(climb_rate(0.54, &c), 0.0);
    assert!((climb_rate(1.0, &c) - 3.0).abs() < 1e-9);
    assert!((climb_rate(0.0, &c) + 1.5).abs() < 1e-9);
}
