use super::*;

fn map_with(bins: &[(usize, u16)]) -> ObstacleMap {
    let mut m = ObstacleMap {
        bins: [1201; SECTORS],
        min_cm: 20,
        max_cm: 1200,
        age_s: 0.05,
    };
    for (i, d) in bins {
        m.bins[*i] = *d;
    }
    m
}

#[test]
fn braking_distance_known_answer() {
    // b = 4 * 9 / 8 = 4.5; c = -2 * 3 * 10 = -60: 0.5 * (-4.5 + sqrt(20.25 + 240)) = 5.817.
    assert!((max_speed_from_distance(8.0, 3.0, 10.0) - 5.8170).abs() < 1e-3);
    assert_eq!(max_speed_from_distance(8.0, 3.0, 0.0), 0.0);
}

#[test]
fn free_space_scales_the_stick_by_the_sensor_range_only() {
    let (cp, lim) = (CpParams::default(), Px4Limits::default());
    let out = constrain([3.0, 0.0], [2.0, 0.0], 0.0, &map_with(&[]), &cp, &lim);
    // Out-of-range sectors count as obstacles at max + 1 cm: ((12.01 - 2) / (10 / 0.95))^2 = 0.904.
    assert!((out[0] - 3.0 * 0.9043).abs() < 1e-3 && out[1].abs() < 1e-9, "{out:?}");
    // Sideways to the nose's sector it is not scaled at all.
    let out = constrain([0.0, -3.0], [0.0, 0.0], 0.0, &map_with(&[]), &cp, &lim);
    assert!(out[0].abs() < 1e-9 && (out[1] + 3.0).abs() < 1e-9, "{out:?}");
}

#[test]
fn an_obstacle_ahead_inside_cp_dist_pushes_back() {
    let (cp, lim) = (CpParams::default(), Px4Limits::default());
    // A wall 1.5 m ahead across five bins (inside CP_DIST 2 m), flying at it at 2 m/s.
    let wall: Vec<(usize, u16)> = [70, 71, 0, 1, 2].iter().map(|i| (*i, 150)).collect();
    let out = constrain([3.0, 0.0], [2.0, 0.0], 0.0, &map_with(&wall), &cp, &lim);
    assert!(out[0] < 0.0, "must decelerate: {out:?}");
}

#[test]
fn an_obstacle_far_ahead_brakes_a_fast_vehicle_before_cp_dist() {
    let (cp, lim) = (CpParams::default(), Px4Limits::default());
    let wall: Vec<(usize, u16)> = [70, 71, 0, 1, 2].iter().map(|i| (*i, 500)).collect();
    // At 8 m/s, 5 m is too short to stop 2 m short: the sum must brake.
    let out = constrain([3.0, 0.0], [8.0, 0.0], 0.0, &map_with(&wall), &cp, &lim);
    assert!(out[0] < 0.0, "{out:?}");
    // At 1 m/s it may still accelerate, less than the stick asks.
    let out = constrain([3.0, 0.0], [1.0, 0.0], 0.0, &map_with(&wall), &cp, &lim);
    assert!(out[0] > 0.0 && out[0] < 3.0, "{out:?}");
}

#[test]
fn no_data_stops_the_vehicle() {
    let (cp, lim) = (CpParams::default(), Px4Limits::default());
    let mut m = map_with(&[]);
    m.bins = [u16::MAX; SECTORS];
    assert_eq!(constrain([3.0, 0.0], [0.0, 0.0], 0.0, &m, &cp, &lim), [0.0, 0.0]);
}
