//! Tests of the cost matrix: known answers from docs/planner.md §5 / §15 and AV's unit tests, plus per-term checks.

use super::*;
use crate::polar::{CellIndex, polar_histogram_to_cartesian, polar_to_index};
use crate::smoothing::pad_polar_matrix;

fn av_params() -> CostParams {
    CostParams {
        yaw_cost: 2.5,
        pitch_cost: 10.0,
        velocity_cost: 1200.0,
        obstacle_cost_m: 5.0,
    }
}

fn ctx(goal: Vector3<f32>, velocity: Vector3<f32>, facing: bool) -> CostContext {
    let inputs = CostInputs {
        goal,
        origin: Vector3::zeros(),
        velocity,
        closest_pt: goal,
    };
    CostContext::new(&inputs, facing)
}

fn matrix(hist: &Histogram, inputs: &CostInputs, k: &CostParams, radius: usize) -> Box<[f32; GRID_CELLS]> {
    let mut total = Box::new([0.0f32; GRID_CELLS]);
    cost_matrix(
        hist,
        inputs,
        k,
        radius,
        0.2,
        15.0,
        &mut CostScratch::default(),
        &mut total,
    );
    total
}

#[test]
fn row_steps_match_spec() {
    let s = row_steps();
    let expect_half = [19, 6, 4, 3, 2, 2, 2, 1, 1, 1, 1, 1, 1, 1, 1];
    for (e, &x) in expect_half.iter().enumerate() {
        assert_eq!(s[e], x, "row {e}");
        assert_eq!(s[GRID_E - 1 - e], x, "row {}", GRID_E - 1 - e);
    }
}

#[test]
fn distance_cost_sample_values() {
    let k = CostParams::default();
    for (d, expect) in [
        (0.2, 9964.0),
        (2.0, 9942.0),
        (6.0, 9642.0),
        (8.5, 5000.0),
        (10.0, 840.0),
        (12.0, 192.0),
        (15.0, 58.0),
    ] {
        let c = distance_cost(d, &k);
        assert!((c - expect).abs() < 1.0, "D = {d}: {c}");
    }
    assert_eq!(distance_cost(0.0, &k), 0.0);
}

#[test]
fn known_answer_distance_cost_order() {
    // AV CostfunctionDistanceCost: no obstacle costs 0, at k_obs = 5 an obstacle at 3 m costs more than at 5 m.
    let c = ctx(Vector3::new(0.0, 5.0, 0.0), Vector3::zeros(), true);
    let cand = PolarDeg::new(0.0, 0.0, 1.0);
    let k = av_params();
    let (d0, _) = cost_function(&cand, 0.0, &c, &k);
    let (d3, _) = cost_function(&cand, 3.0, &c, &k);
    let (d5, _) = cost_function(&cand, 5.0, &c, &k);
    assert_eq!(d0, 0.0);
    assert!(d0 < d3 && d5 < d3);
}

#[test]
fn known_answer_goal_and_velocity_costs() {
    let k = av_params();
    let cand = PolarDeg::new(0.0, 0.0, 1.0); // North
    let toward = cost_function(
        &cand,
        0.0,
        &ctx(Vector3::new(0.0, 5.0, 0.0), Vector3::zeros(), true),
        &k,
    )
    .1;
    let diagonal = cost_function(
        &cand,
        0.0,
        &ctx(Vector3::new(3.0, 3.0, 0.0), Vector3::zeros(), true),
        &k,
    )
    .1;
    assert!(toward < diagonal);
    let goal = Vector3::new(0.0, 5.0, 0.0);
    let along = cost_function(&cand, 0.0, &ctx(goal, Vector3::new(0.0, 1.0, 0.0), true), &k).1;
    let across = cost_function(&cand, 0.0, &ctx(goal, Vector3::new(1.0, 0.0, 0.0), true), &k).1;
    assert!(along < across);
    // Velocity cost: 0 when aligned, 2 k_v |V| when opposite.
    let c = ctx(goal, Vector3::new(0.0, 3.0, 0.0), true);
    let unit_n = Vector3::new(0.0, 1.0, 0.0);
    assert!(c.velocity_term(&unit_n, &k).abs() < 1e-2);
    assert!((c.velocity_term(&-unit_n, &k) - 2.0 * 1200.0 * 3.0).abs() < 1e-2);
}

#[test]
fn yaw_cost_splits_between_goal_and_line_unless_an_obstacle_faces_the_goal() {
    let k = CostParams::default();
    let inputs = CostInputs {
        goal: Vector3::new(0.0, 20.0, 0.0),
        origin: Vector3::zeros(),
        velocity: Vector3::zeros(),
        closest_pt: Vector3::new(20.0, 0.0, 0.0),
    };
    // Candidate 90 deg (East) = on the line direction, 90 deg from the goal.
    let free = CostContext::new(&inputs, false);
    let (yaw, line) = free.yaw_terms(90.0, &k);
    assert_eq!((yaw, line), (0.5 * 3.0 * 8100.0, 0.0));
    let blocked = CostContext::new(&inputs, true);
    assert_eq!(blocked.yaw_terms(90.0, &k), (3.0 * 8100.0, 0.0));
}

#[test]
fn pitch_cost_grows_near_the_goal() {
    let k = CostParams::default();
    let far = ctx(Vector3::new(0.0, 10.0, 0.0), Vector3::zeros(), true);
    let near = ctx(Vector3::new(0.0, 2.5, 0.0), Vector3::zeros(), true);
    assert_eq!(far.pitch_term(9.0, &k), 25.0 * 81.0);
    assert!((near.pitch_term(9.0, &k) - 4.0 * 25.0 * 81.0).abs() < 1e-2);
}

#[test]
fn obstacle_facing_goal_window() {
    let origin = Vector3::zeros();
    let goal = Vector3::new(0.0, 20.0, 0.0);
    let with = |e: f32, z: f32, r: f32| {
        let p = polar_histogram_to_cartesian(&PolarDeg::new(e, z, r), &origin);
        let h = Histogram::from_points(&[p], &origin);
        obstacle_facing_goal(&h, &goal, &origin, 0.2, 15.0)
    };
    assert!(with(0.0, 0.0, 5.0));
    assert!(with(10.0, 30.0, 5.0)); // +2 rows, +5 columns
    assert!(with(-12.0, -30.0, 5.0));
    assert!(!with(0.0, 40.0, 5.0));
    assert!(!with(20.0, 0.0, 5.0));
    assert!(!with(0.0, 0.0, 15.5), "beyond max range");
    assert!(!with(0.0, 0.0, 0.1), "below min range");
}

#[test]
fn known_answer_empty_histogram_minimum_at_goal_and_growing_away() {
    // docs/planner.md §15 / AV getCostMatrixNoObstacles: goal 5 m North, velocity 1 m/s East, smoothing 30 deg.
    let inputs = CostInputs {
        goal: Vector3::new(0.0, 5.0, 0.0),
        origin: Vector3::zeros(),
        velocity: Vector3::new(1.0, 0.0, 0.0),
        closest_pt: Vector3::new(0.0, 5.0, 0.0),
    };
    let m = matrix(&Histogram::new(), &inputs, &av_params(), 5);
    let (imin, _) = m
        .iter()
        .enumerate()
        .fold((0, f32::INFINITY), |a, (i, &c)| if c < a.1 { (i, c) } else { a });
    let (min_e, min_z) = (imin / GRID_Z, imin % GRID_Z);
    let best = polar_to_index(cartesian_to_polar_histogram(&inputs.goal, &inputs.origin), ALPHA_RES);
    assert!(
        min_e.abs_diff(best.e) <= 1 && min_z.abs_diff(best.z) <= 1,
        "min at {min_e},{min_z}, goal {best:?}"
    );

    let r = 3;
    let p = pad_polar_matrix(&m[..], GRID_E, GRID_Z, r);
    let pc = GRID_Z + 2 * r;
    let row = |e: usize| &p[e * pc..(e + 1) * pc];
    let (be, bz) = (min_e + r, min_z + r);
    let all = |a: &[f32], b: &[f32], slack: f32| a.iter().zip(b).all(|(x, y)| *x > *y - slack);
    assert!(all(row(be + 2), row(be + 1), 0.0));
    assert!(all(row(be + 3), row(be + 2), 0.0));
    assert!(all(row(be - 2), row(be), 1.0));
    assert!(all(row(be - 3), row(be), 2.0));
    let col = |z: usize| -> Vec<f32> { (0..GRID_E).map(|e| p[(e + r) * pc + z]).collect() };
    assert!(all(&col(bz + 10), &col(bz + 1), 0.0));
    assert!(all(&col(bz + 20), &col(bz + 10), 0.0));
    assert!(all(&col(bz - 10), &col(bz), 1.0));
    assert!(all(&col(bz - 20), &col(bz), 10.0));
}

#[test]
fn stepped_rows_are_linear_between_evaluated_columns() {
    let k = CostParams::default();
    let inputs = CostInputs {
        goal: Vector3::new(7.0, 3.0, 2.0),
        origin: Vector3::zeros(),
        velocity: Vector3::new(0.5, 1.0, 0.0),
        closest_pt: Vector3::new(7.0, 3.0, 2.0),
    };
    let m = matrix(&Histogram::new(), &inputs, &k, 7);
    let c = CostContext::new(&inputs, false);
    let direct = |e: usize, z: usize| cost_function(&index_to_polar(e, z, ALPHA_RES, 1.0), 0.0, &c, &k).1;
    // Row 0 (step 19): columns 0, 19, 38, 57 are evaluated; 10 lies between 0 and 19; 58-59 wrap to 0.
    for z in [0, 19, 38, 57] {
        assert!((m[z] - direct(0, z)).abs() <= 1e-3 * direct(0, z).abs(), "col {z}");
    }
    let lin = direct(0, 0) + (direct(0, 19) - direct(0, 0)) / 19.0 * 10.0;
    assert!((m[10] - lin).abs() <= 1e-3 * lin.abs());
    let wrap = direct(0, 57) + (direct(0, 0) - direct(0, 57)) / 3.0 * 2.0;
    assert!((m[59] - wrap).abs() <= 1e-3 * wrap.abs());
    // Rows with step 1 are evaluated everywhere.
    assert_eq!(m[15 * GRID_Z + 7], direct(15, 7));
}

#[test]
fn only_the_distance_cost_is_smoothed() {
    let k = CostParams::default();
    let origin = Vector3::new(0.0, 0.0, 5.0);
    let inputs = CostInputs {
        goal: Vector3::new(0.0, 30.0, 5.0),
        origin,
        velocity: Vector3::zeros(),
        closest_pt: Vector3::new(0.0, 30.0, 5.0),
    };
    let obstacle = polar_histogram_to_cartesian(&PolarDeg::new(3.0, 93.0, 4.0), &origin); // East
    let hist = Histogram::from_points(&[obstacle], &origin);
    let with = matrix(&hist, &inputs, &k, 7);
    let without = matrix(&Histogram::new(), &inputs, &k, 7);
    let cell = CellIndex { e: 15, z: 45 };
    let i = cell.e * GRID_Z + cell.z;
    let dcost = distance_cost(4.0, &k);
    assert!(((with[i] - without[i]) - dcost).abs() < 0.05 * dcost / 64.0 + 1.0);
    // 3 cells away the distance cost is (5/8)^2 of the centre; outside the radius nothing changes.
    let j = (cell.e + 3) * GRID_Z + cell.z + 3;
    assert!(((with[j] - without[j]) - dcost * 25.0 / 64.0).abs() < 2.0);
    let far = cell.e * GRID_Z + cell.z - 8;
    assert_eq!(with[far], without[far]);
}

#[test]
fn known_answer_best_candidates() {
    // AV getBestCandidatesFromCostMatrix.
    let mut m = Box::new([10.0f32; GRID_CELLS]);
    m[2] = 1.1;
    m[1] = 2.5;
    m[GRID_Z + 2] = 3.8;
    m[GRID_Z] = 4.7;
    m[2 * GRID_Z + 2] = 4.9;
    let mut out = Vec::new();
    best_candidates(&m, 4, &mut out);
    let costs: Vec<f32> = out.iter().map(|c| c.cost).collect();
    assert_eq!(costs, vec![1.1, 2.5, 3.8, 4.7]);
    assert_eq!((out[0].e_deg, out[0].z_deg), (-87.0, -165.0));
}

#[test]
fn best_candidates_break_ties_by_scan_order() {
    let mut m = Box::new([5.0f32; GRID_CELLS]);
    m[100] = 1.0;
    let mut out = Vec::new();
    best_candidates(&m, 3, &mut out);
    assert_eq!(out[0].cost, 1.0);
    // The two ties are the first two cells in scan order.
    assert_eq!((out[1].e_deg, out[1].z_deg), (-87.0, -177.0));
    assert_eq!((out[2].e_deg, out[2].z_deg), (-87.0, -171.0));
}

#[test]
fn portable_fill_equals_the_dispatched_fill() {
    // The AVX2 build and the baseline build of the same body must agree bit for bit.
    let origin = Vector3::new(0.3, -0.2, 2.0);
    let pts: Vec<Vector3<f32>> = (0..500)
        .map(|i| {
            let a = i as f32 * 0.37;
            origin + Vector3::new(a.sin() * (3.0 + (i % 7) as f32), a.cos() * 4.0, (i % 11) as f32 - 4.0)
        })
        .collect();
    let hist = Histogram::from_points(&pts, &origin);
    let inputs = CostInputs {
        goal: Vector3::new(3.0, 20.0, 2.5),
        origin,
        velocity: Vector3::new(0.5, 2.0, -0.1),
        closest_pt: Vector3::new(1.0, 5.0, 2.5),
    };
    let k = CostParams::default();
    let ctx = CostContext::new(&inputs, false);
    let (mut o1, mut o2) = (Box::new([0.0f32; GRID_CELLS]), Box::new([0.0f32; GRID_CELLS]));
    let (mut d1, mut d2) = (vec![0.0f32; GRID_CELLS], vec![0.0f32; GRID_CELLS]);
    fill_matrices(&hist, &ctx, &k, &mut o1, &mut d1);
    fill_matrices_body(&hist, &ctx, &k, &mut o2, &mut d2);
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&o1[..]), bits(&o2[..]));
    assert_eq!(bits(&d1), bits(&d2));
}
