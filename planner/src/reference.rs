//! Straightforward (slow) transcriptions of the hot planner stages, kept only for tests: the optimised code in
//! [`super::histogram`], [`super::cost`] and [`super::smoothing`] must give **bit-identical** results.
//!
//! Each function follows docs/planner.md §4-5 literally, cell by cell, with the exact formulas of the public API
//! ([`cost_function`], [`polar_to_index`], [`cartesian_to_polar_histogram`]).

use nalgebra::Vector3;

use super::cost::{Candidate, CostContext, CostInputs, cost_function};
use super::histogram::Histogram;
use super::params::CostParams;
use super::polar::{
    ALPHA_RES, CellIndex, DEG_TO_RAD, GRID_CELLS, GRID_E, GRID_Z, PolarDeg, cartesian_to_polar_histogram,
    index_to_polar, polar_to_index,
};
use super::smoothing::pad_polar_matrix;

/// Histogram by the definition: exact cell of every point, sum of ranges in input order, then the mean.
pub fn histogram(xs: &[f32], ys: &[f32], zs: &[f32], origin: &Vector3<f32>) -> Histogram {
    let mut sum = vec![0.0f32; GRID_CELLS];
    let mut count = vec![0u32; GRID_CELLS];
    for ((&x, &y), &z) in xs.iter().zip(ys).zip(zs) {
        let p = cartesian_to_polar_histogram(&Vector3::new(x, y, z), origin);
        let c = polar_to_index(p, ALPHA_RES);
        sum[c.e * GRID_Z + c.z] += p.r_m;
        count[c.e * GRID_Z + c.z] += 1;
    }
    let mut h = Histogram::new();
    for e in 0..GRID_E {
        for z in 0..GRID_Z {
            let i = e * GRID_Z + z;
            if count[i] > 0 {
                h.set(CellIndex { e, z }, sum[i] / count[i] as f32);
            }
        }
    }
    h
}

/// The goal-facing test cell by cell: [`polar_to_index`] of each of the 5 x 11 directions around the goal.
pub fn obstacle_facing_goal(
    hist: &Histogram,
    goal: &Vector3<f32>,
    origin: &Vector3<f32>,
    min_m: f32,
    max_m: f32,
) -> bool {
    let g = cartesian_to_polar_histogram(goal, origin);
    for j in -2..=2 {
        for i in -5..=5 {
            let p = PolarDeg::new(g.e_deg + (j * ALPHA_RES) as f32, g.z_deg + (i * ALPHA_RES) as f32, 0.0);
            let d = hist.at(polar_to_index(p, ALPHA_RES));
            if d > min_m && d < max_m {
                return true;
            }
        }
    }
    false
}

/// Two-pass conic smoothing as the original's kernel loops, each kernel sum accumulated in f64 with the
/// integer weights `R + 1 - |k|` and scaled by `1 / (R + 1)` before rounding to f32. For the cost magnitudes
/// of the planner the f64 sums are exact, so any summation order gives these same bits.
pub fn smooth(m: &mut [f32], rows: usize, cols: usize, radius: usize) {
    let n = radius;
    let mut p = pad_polar_matrix(m, rows, cols, n);
    let (pr, pc) = (rows + 2 * n, cols + 2 * n);
    let w = |k: usize| (n + 1) as f64 - (k as f64 - n as f64).abs();
    let inv = 1.0 / (n + 1) as f64;
    let mut col = vec![0.0f32; pr];
    for c in 0..pc {
        for (r, v) in col.iter_mut().enumerate() {
            *v = p[r * pc + c];
        }
        for r in 0..rows {
            let s: f64 = (0..=2 * n).map(|k| w(k) * col[r + k] as f64).sum();
            p[(r + n) * pc + c] = (s * inv) as f32;
        }
    }
    for r in 0..rows {
        let row = &p[(r + n) * pc..(r + n + 1) * pc];
        for c in 0..cols {
            let s: f64 = (0..=2 * n).map(|k| w(k) * row[c + k] as f64).sum();
            m[r * cols + c] = (s * inv) as f32;
        }
    }
}

/// Cost matrix cell by cell: [`cost_function`] at the evaluated columns of each row (every
/// `round(1/cos(e))`-th), linear interpolation in between and over the wrap, smoothing of the distance part.
#[allow(clippy::too_many_arguments)]
pub fn cost_matrix(
    hist: &Histogram,
    inputs: &CostInputs,
    k: &CostParams,
    radius: usize,
    min_m: f32,
    max_m: f32,
) -> Vec<f32> {
    let facing = obstacle_facing_goal(hist, &inputs.goal, &inputs.origin, min_m, max_m);
    let ctx = CostContext::new(inputs, facing);
    let mut other = vec![f32::NAN; GRID_CELLS];
    let mut dist = vec![f32::NAN; GRID_CELLS];
    for e in 0..GRID_E {
        let bin_width = (index_to_polar(e, 0, ALPHA_RES, 1.0).e_deg * DEG_TO_RAD).cos();
        let step = (1.0 / bin_width).round() as usize;
        let row = e * GRID_Z;
        let mut evaluated = Vec::new();
        for z in (0..GRID_Z).step_by(step) {
            let cand = index_to_polar(e, z, ALPHA_RES, 1.0);
            let (d, o) = cost_function(&cand, hist.at(CellIndex { e, z }), &ctx, k);
            dist[row + z] = d;
            other[row + z] = o;
            evaluated.push(z);
        }
        // Segments between evaluated columns, then the wrap segment back to column 0 (length 60 - last).
        for m in [&mut other, &mut dist] {
            for pair in evaluated.windows(2) {
                let (a, b) = (pair[0], pair[1]);
                let grad = (m[row + b] - m[row + a]) / step as f32;
                for i in 1..step {
                    m[row + a + i] = m[row + a] + grad * i as f32;
                }
            }
            let last = *evaluated.last().expect("column 0 is always evaluated");
            let span = GRID_Z - last;
            let grad = (m[row] - m[row + last]) / span as f32;
            for i in 1..span {
                m[row + last + i] = m[row + last] + grad * i as f32;
            }
        }
    }
    smooth(&mut dist, GRID_E, GRID_Z, radius);
    other.iter().zip(&dist).map(|(o, d)| o + d).collect()
}

/// The `n` cheapest cells: all cells sorted by `(cost.total_cmp, index)`, the first `n` kept.
pub fn best_candidates(total: &[f32], n: usize) -> Vec<Candidate> {
    let mut all: Vec<(f32, usize)> = total.iter().copied().zip(0..).collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    all.truncate(n);
    all.iter()
        .map(|&(cost, i)| {
            let p = index_to_polar(i / GRID_Z, i % GRID_Z, ALPHA_RES, 1.0);
            Candidate {
                cost,
                e_deg: p.e_deg,
                z_deg: p.z_deg,
            }
        })
        .collect()
}
