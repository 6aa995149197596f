//! Bit-exact equivalence of the optimised hot path (histogram, cost matrix, smoothing, candidate selection)
//! with the straightforward transcriptions in [`super::reference`], on random inputs and realistic scenes.

use nalgebra::Vector3;
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::cost::{CostInputs, CostScratch, best_candidates, cost_matrix, obstacle_facing_goal};
use super::histogram::{Histogram, HistogramScratch};
use super::params::CostParams;
use super::polar::GRID_CELLS;
use super::reference;
use super::select::{SelectScratch, best_candidates_lazy};
use super::smoothing::{SmoothScratch, smooth_fast};

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// A camera-like cloud: rays from `eye` in a cone around `yaw` hitting the floor (z = 0) and two boxes, plus
/// a scatter of remembered points around the eye.
fn scene(rng: &mut ChaCha8Rng, eye: Vector3<f32>) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let boxes: Vec<(Vector3<f32>, Vector3<f32>)> = (0..2)
        .map(|_| {
            let c = eye + Vector3::new(rng.random_range(-6.0..6.0), rng.random_range(3.0..12.0), 0.0);
            let h = Vector3::new(
                rng.random_range(0.5..3.0),
                rng.random_range(0.5..3.0),
                rng.random_range(2.0..12.0),
            );
            (Vector3::new(c.x - h.x, c.y - h.y, 0.0), c + h)
        })
        .collect();
    let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..24 {
        for i in 0..32 {
            let az = (i as f32 - 15.5) * 0.032;
            let el = (j as f32 - 11.5) * 0.032;
            let d = Vector3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin());
            let mut t = if d.z < 0.0 { -eye.z / d.z } else { f32::INFINITY };
            for (lo, hi) in &boxes {
                let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
                for k in 0..3 {
                    let (a, b) = ((lo[k] - eye[k]) / d[k], (hi[k] - eye[k]) / d[k]);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                }
                if t0 <= t1 {
                    t = t.min(t0);
                }
            }
            if t > 0.2 && t < 15.0 {
                let p = eye + d * t;
                xs.push(p.x);
                ys.push(p.y);
                zs.push(p.z);
            }
        }
    }
    for _ in 0..rng.random_range(0..300) {
        xs.push(eye.x + rng.random_range(-15.0..15.0));
        ys.push(eye.y + rng.random_range(-15.0..15.0));
        zs.push(rng.random_range(0.0..eye.z + 3.0));
    }
    (xs, ys, zs)
}

fn random_vec(rng: &mut ChaCha8Rng, r: f32) -> Vector3<f32> {
    Vector3::new(
        rng.random_range(-r..r),
        rng.random_range(-r..r),
        rng.random_range(-r..r),
    )
}

/// Checks every hot stage against its reference at one origin.
fn check_stages(xs: &[f32], ys: &[f32], zs: &[f32], inputs: &CostInputs, k: &CostParams, radius: usize) {
    let mut hist = Histogram::new();
    hist.build_from_soa(xs, ys, zs, &inputs.origin, &mut HistogramScratch::default());
    let want = reference::histogram(xs, ys, zs, &inputs.origin);
    assert_eq!(bits(hist.cells()), bits(want.cells()), "histogram");

    let mut total = Box::new([0.0f32; GRID_CELLS]);
    let mut scratch = CostScratch::default();
    cost_matrix(&hist, inputs, k, radius, 0.2, 15.0, &mut scratch, &mut total);
    let want = reference::cost_matrix(&hist, inputs, k, radius, 0.2, 15.0);
    assert_eq!(bits(&total[..]), bits(&want), "cost matrix at {inputs:?}");

    for n in [1, 8, 13] {
        let mut got = Vec::new();
        best_candidates(&total, n, &mut got);
        assert_eq!(got, reference::best_candidates(&total[..], n), "n = {n}");
    }
}

#[test]
fn realistic_scenes_match_the_reference_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let k = CostParams::default();
    for _ in 0..30 {
        let eye = Vector3::new(
            rng.random_range(-5.0..5.0),
            rng.random_range(-5.0..5.0),
            rng.random_range(1.0..6.0),
        );
        let (xs, ys, zs) = scene(&mut rng, eye);
        let goal = eye + Vector3::new(rng.random_range(-10.0..10.0), 30.0, 0.0);
        // The vehicle itself and tree-node-like origins (2 m steps, 2 m edge velocities).
        for step in 0..6 {
            let dir = random_vec(&mut rng, 1.0).normalize() * 2.0;
            let origin = eye + random_vec(&mut rng, 1.0) * step as f32 * 2.0;
            let inputs = CostInputs {
                goal,
                origin,
                velocity: if step == 0 { Vector3::new(0.0, 3.0, 0.0) } else { dir },
                closest_pt: if step % 2 == 0 { goal } else { eye },
            };
            check_stages(&xs, &ys, &zs, &inputs, &k, 7);
        }
    }
}

#[test]
fn ties_and_uniform_matrices_select_like_the_reference() {
    let mut flat = Box::new([5.0f32; GRID_CELLS]);
    for n in [1, 8, 60, 1799, 1800, 2000] {
        let mut got = Vec::new();
        best_candidates(&flat, n, &mut got);
        assert_eq!(got, reference::best_candidates(&flat[..], n));
    }
    flat[1799] = -0.0;
    flat[0] = 0.0;
    let mut got = Vec::new();
    best_candidates(&flat, 3, &mut got);
    assert_eq!(got, reference::best_candidates(&flat[..], 3));
}

/// The lazy selection of a tree expansion against the reference cost matrix and selection, for several `n`.
fn check_lazy(xs: &[f32], ys: &[f32], zs: &[f32], inputs: &CostInputs, k: &CostParams, radius: usize) {
    let mut hist = Histogram::new();
    hist.build_from_soa(xs, ys, zs, &inputs.origin, &mut HistogramScratch::default());
    let total = reference::cost_matrix(&hist, inputs, k, radius, 0.2, 15.0);
    let mut scratch = SelectScratch::default();
    for n in [1, 8, 13, 100] {
        let mut got = Vec::new();
        best_candidates_lazy(&hist, inputs, k, radius, 0.2, 15.0, n, &mut scratch, &mut got);
        assert_eq!(got, reference::best_candidates(&total, n), "n = {n} at {inputs:?}");
    }
}

#[test]
fn lazy_selection_matches_the_reference_on_realistic_scenes() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for scene_no in 0..30 {
        let eye = Vector3::new(
            rng.random_range(-5.0..5.0),
            rng.random_range(-5.0..5.0),
            rng.random_range(1.0..6.0),
        );
        let (xs, ys, zs) = scene(&mut rng, eye);
        // Goals ahead, behind (azimuth wrap at South) and steeply above or below (pole mirroring).
        let goal = match scene_no % 3 {
            0 => eye + Vector3::new(rng.random_range(-10.0..10.0), 30.0, 0.0),
            1 => eye + Vector3::new(rng.random_range(-3.0..3.0), -30.0, rng.random_range(-3.0..3.0)),
            _ => eye + Vector3::new(1.0, 2.0, if scene_no % 2 == 0 { 20.0 } else { -20.0 }),
        };
        for step in 0..6 {
            let dir = random_vec(&mut rng, 1.0).normalize() * 2.0;
            let origin = eye + random_vec(&mut rng, 1.0) * step as f32 * 2.0;
            let inputs = CostInputs {
                goal,
                origin,
                velocity: if step == 0 { Vector3::new(0.0, 3.0, 0.0) } else { dir },
                closest_pt: if step % 2 == 0 { goal } else { eye },
            };
            check_lazy(
                &xs,
                &ys,
                &zs,
                &inputs,
                &CostParams::default(),
                [7, 7, 3, 1, 0, 12][step],
            );
        }
    }
}

#[test]
fn lazy_selection_of_every_cell_matches_the_reference() {
    // More candidates than cells: every row is smoothed and all 1800 cells come out in order.
    let eye = Vector3::new(0.5, -1.0, 4.0);
    let (xs, ys, zs) = scene(&mut ChaCha8Rng::seed_from_u64(7), eye);
    let mut hist = Histogram::new();
    hist.build_from_soa(&xs, &ys, &zs, &eye, &mut HistogramScratch::default());
    let inputs = CostInputs {
        goal: eye + Vector3::new(3.0, 25.0, 1.0),
        origin: eye,
        velocity: Vector3::new(0.5, 2.0, 0.0),
        closest_pt: eye + Vector3::new(0.0, 25.0, 0.0),
    };
    let k = CostParams::default();
    let total = reference::cost_matrix(&hist, &inputs, &k, 7, 0.2, 15.0);
    let mut got = Vec::new();
    best_candidates_lazy(
        &hist,
        &inputs,
        &k,
        7,
        0.2,
        15.0,
        2000,
        &mut SelectScratch::default(),
        &mut got,
    );
    assert_eq!(got.len(), GRID_CELLS);
    assert_eq!(got, reference::best_candidates(&total, 2000));
}

#[test]
fn lazy_selection_falls_back_on_non_finite_costs() {
    // An infinite velocity makes the "other" costs non-finite: the lazy search must give the full path's answer.
    let (xs, ys, zs) = scene(&mut ChaCha8Rng::seed_from_u64(6), Vector3::new(0.0, 0.0, 3.0));
    let mut hist = Histogram::new();
    let origin = Vector3::new(0.0, 0.0, 3.0);
    hist.build_from_soa(&xs, &ys, &zs, &origin, &mut HistogramScratch::default());
    let inputs = CostInputs {
        goal: Vector3::new(0.0, 30.0, 3.0),
        origin,
        velocity: Vector3::new(f32::INFINITY, 0.0, 0.0),
        closest_pt: Vector3::new(0.0, 30.0, 3.0),
    };
    let k = CostParams::default();
    let mut total = Box::new([0.0f32; GRID_CELLS]);
    cost_matrix(
        &hist,
        &inputs,
        &k,
        7,
        0.2,
        15.0,
        &mut CostScratch::default(),
        &mut total,
    );
    let (mut want, mut got) = (Vec::new(), Vec::new());
    best_candidates(&total, 8, &mut want);
    best_candidates_lazy(
        &hist,
        &inputs,
        &k,
        7,
        0.2,
        15.0,
        8,
        &mut SelectScratch::default(),
        &mut got,
    );
    let bits = |c: &[super::cost::Candidate]| {
        c.iter()
            .map(|c| (c.cost.to_bits(), c.e_deg, c.z_deg))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&got), bits(&want));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn goal_facing_test_matches_the_reference(
        seed in any::<u64>(), n_pts in 1usize..300, up in -1.0f32..1.0, min_m in 0.0f32..3.0
    ) {
        // Goals in every direction, including straight up and down (pole folds) and South (azimuth wrap).
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let origin = random_vec(&mut rng, 10.0);
        let cloud: Vec<Vector3<f32>> = (0..n_pts).map(|_| origin + random_vec(&mut rng, 12.0)).collect();
        let hist = Histogram::from_points(&cloud, &origin);
        let horizontal = random_vec(&mut rng, 1.0);
        let dir = Vector3::new(horizontal.x, horizontal.y, 0.0) * (1.0 - up.abs()) + Vector3::new(0.0, 0.0, up);
        for goal in [origin + dir * 20.0, origin + Vector3::new(0.0, -20.0, up), origin + Vector3::new(0.0, 0.0, 5.0)] {
            prop_assert_eq!(
                obstacle_facing_goal(&hist, &goal, &origin, min_m, 15.0),
                reference::obstacle_facing_goal(&hist, &goal, &origin, min_m, 15.0)
            );
        }
    }

    #[test]
    fn random_clouds_select_lazily_like_the_reference(
        seed in any::<u64>(), n_pts in 0usize..400, radius in 0usize..9, goal_d in 0.5f32..40.0,
        facing_line in any::<bool>()
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let origin = random_vec(&mut rng, 10.0);
        let cloud: Vec<Vector3<f32>> = (0..n_pts).map(|_| origin + random_vec(&mut rng, 20.0)).collect();
        let xs: Vec<f32> = cloud.iter().map(|p| p.x).collect();
        let ys: Vec<f32> = cloud.iter().map(|p| p.y).collect();
        let zs: Vec<f32> = cloud.iter().map(|p| p.z).collect();
        let goal = origin + random_vec(&mut rng, 1.0).normalize() * goal_d;
        let k = CostParams {
            yaw_cost: rng.random_range(0.0..5.0),
            pitch_cost: rng.random_range(0.0..30.0),
            velocity_cost: rng.random_range(0.0..8000.0),
            obstacle_cost_m: rng.random_range(1.0..10.0),
        };
        let inputs = CostInputs {
            goal,
            origin,
            velocity: random_vec(&mut rng, 4.0),
            closest_pt: if facing_line { origin + random_vec(&mut rng, 10.0) } else { goal },
        };
        check_lazy(&xs, &ys, &zs, &inputs, &k, radius);
    }

    #[test]
    fn random_clouds_match_the_reference(
        seed in any::<u64>(), n_pts in 0usize..400, radius in 1usize..9,
        goal_d in 0.5f32..40.0, facing_line in any::<bool>()
    ) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let origin = random_vec(&mut rng, 10.0);
        let cloud: Vec<Vector3<f32>> = (0..n_pts).map(|_| origin + random_vec(&mut rng, 20.0)).collect();
        let xs: Vec<f32> = cloud.iter().map(|p| p.x).collect();
        let ys: Vec<f32> = cloud.iter().map(|p| p.y).collect();
        let zs: Vec<f32> = cloud.iter().map(|p| p.z).collect();
        let goal = origin + random_vec(&mut rng, 1.0).normalize() * goal_d;
        let k = CostParams {
            yaw_cost: rng.random_range(0.0..5.0),
            pitch_cost: rng.random_range(0.0..30.0),
            velocity_cost: rng.random_range(0.0..8000.0),
            obstacle_cost_m: rng.random_range(1.0..10.0),
        };
        let inputs = CostInputs {
            goal,
            origin,
            velocity: random_vec(&mut rng, 4.0),
            closest_pt: if facing_line { origin + random_vec(&mut rng, 10.0) } else { goal },
        };
        check_stages(&xs, &ys, &zs, &inputs, &k, radius);
    }

    #[test]
    fn random_cost_matrices_select_like_the_reference(
        seed in any::<u64>(), n in 1usize..40, levels in 1u32..2000
    ) {
        // Quantised costs make many exact ties.
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut total = Box::new([0.0f32; GRID_CELLS]);
        for c in total.iter_mut() {
            *c = rng.random_range(0..levels) as f32 * 0.5 - 100.0;
        }
        let mut got = Vec::new();
        best_candidates(&total, n, &mut got);
        prop_assert_eq!(got, reference::best_candidates(&total[..], n));
    }

    #[test]
    fn smoothing_matches_the_reference(seed in any::<u64>(), radius in 1usize..9, fill in 0.0f64..1.0) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut m: Vec<f32> = (0..GRID_CELLS)
            .map(|_| if rng.random_bool(fill) { rng.random_range(5.0f32..10_000.0) } else { 0.0 })
            .collect();
        let mut want = m.clone();
        reference::smooth(&mut want, 30, 60, radius);
        smooth_fast(&mut m, 30, 60, radius, &mut SmoothScratch::default());
        prop_assert_eq!(bits(&m), bits(&want));
    }
}
