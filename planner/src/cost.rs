//! The cost matrix of 3DVFH* (docs/planner.md §5, AV `getCostMatrix` / `costFunction` /
//! `getBestCandidatesFromCostMatrix`): per direction, a distance cost from the histogram (smoothed) plus velocity,
//! yaw, yaw-to-line and pitch costs (not smoothed). Lower is better.
//!
//! Matrices are row-major `(e, z)` 30 x 60 like the histogram. Positions and velocities are ENU.

use std::sync::OnceLock;

use nalgebra::Vector3;

use super::histogram::Histogram;
use super::params::CostParams;
use super::polar::{
    ALPHA_RES, CellIndex, DEG_TO_RAD, GRID_CELLS, GRID_E, GRID_Z, PolarDeg, angle_difference,
    cartesian_to_polar_histogram, floor_f32, fold_elevation_deg, index_to_polar, polar_histogram_to_cartesian,
    wrap_180,
};
use super::smoothing::{SmoothScratch, smooth_fast};

/// Where the costs are evaluated from and towards (all ENU, metres or m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostInputs {
    /// Goal position.
    pub goal: Vector3<f32>,
    /// Origin of the histogram (vehicle or tree node).
    pub origin: Vector3<f32>,
    /// Velocity at the origin: the vehicle velocity at the root, the 2 m edge vector at tree nodes.
    pub velocity: Vector3<f32>,
    /// Closest point on the previous-goal-to-goal line (docs/planner.md §7.3), or the goal.
    pub closest_pt: Vector3<f32>,
}

/// Geometry shared by every cost matrix: cell-centre directions and the azimuth step of each row.
struct CellTables {
    /// Normalised unit vector of each cell centre (ENU), as `polarHistogramToCartesian(.., r = 1).normalized()`,
    /// stored as separate x, y, z arrays so the per-cell velocity term vectorises.
    ux: [f32; GRID_CELLS],
    uy: [f32; GRID_CELLS],
    uz: [f32; GRID_CELLS],
    /// Azimuth step per row: `round(1 / cos(row centre elevation))`.
    step: [usize; GRID_E],
}

fn tables() -> &'static CellTables {
    static TABLES: OnceLock<Box<CellTables>> = OnceLock::new();
    TABLES.get_or_init(|| {
        let mut t = Box::new(CellTables {
            ux: [0.0; GRID_CELLS],
            uy: [0.0; GRID_CELLS],
            uz: [0.0; GRID_CELLS],
            step: [1; GRID_E],
        });
        for e in 0..GRID_E {
            for z in 0..GRID_Z {
                let v = polar_histogram_to_cartesian(&index_to_polar(e, z, ALPHA_RES, 1.0), &Vector3::zeros());
                let u = v.normalize();
                (t.ux[e * GRID_Z + z], t.uy[e * GRID_Z + z], t.uz[e * GRID_Z + z]) = (u.x, u.y, u.z);
            }
        }
        for (e, s) in t.step.iter_mut().enumerate() {
            let bin_width = (index_to_polar(e, 0, ALPHA_RES, 1.0).e_deg * DEG_TO_RAD).cos();
            *s = (1.0 / bin_width).round() as usize;
        }
        t
    })
}

/// Azimuth step of each histogram row (19, 6, 4, 3, 2, 2, 2, 1, ... symmetric).
pub fn row_steps() -> [usize; GRID_E] {
    tables().step
}

/// True if any of the 5 x 11 cells around the goal direction (+-2 rows, +-5 columns, each re-wrapped) holds an
/// obstacle with `min_range < dist < max_range` (`is_obstacle_facing_goal`).
pub fn obstacle_facing_goal(
    hist: &Histogram,
    goal: &Vector3<f32>,
    origin: &Vector3<f32>,
    min_m: f32,
    max_m: f32,
) -> bool {
    // `polar_to_index(wrap_polar(..))` of each of the 5 x 11 directions, split into its elevation part (row index
    // and whether the elevation folds over a pole, which turns the azimuth by 180 degrees) and its azimuth part
    // (column index unfolded and folded): the same operations, each done once instead of 55 times.
    let g = cartesian_to_polar_histogram(goal, origin);
    let res = ALPHA_RES as f32;
    let mut rows = [(0usize, false); 5];
    for (row, j) in rows.iter_mut().zip(-2..=2) {
        let (e, fold) = fold_elevation_deg(wrap_180(g.e_deg + (j * ALPHA_RES) as f32));
        let index = floor_f32(e / res + 90.0 / res) as i32;
        *row = (index.clamp(0, 180 / ALPHA_RES - 1) as usize, fold);
    }
    let column = |z: f32| (floor_f32(z / res + 180.0 / res) as i32).clamp(0, 360 / ALPHA_RES - 1) as usize;
    let mut cols = [(0usize, 0usize); 11];
    for (col, i) in cols.iter_mut().zip(-5..=5) {
        let z = wrap_180(g.z_deg + (i * ALPHA_RES) as f32);
        let folded = if z < 0.0 { z + 180.0 } else { z - 180.0 };
        *col = (column(z), column(folded));
    }
    rows.iter().any(|&(e, fold)| {
        cols.iter().any(|&(z, zf)| {
            let d = hist.at(CellIndex {
                e,
                z: if fold { zf } else { z },
            });
            d > min_m && d < max_m
        })
    })
}

/// Per-origin terms of [`cost_function`] that do not depend on the candidate.
#[derive(Debug, Clone, Copy)]
pub struct CostContext {
    facing_goal: PolarDeg,
    goal_distance: f32,
    facing_line: PolarDeg,
    velocity: Vector3<f32>,
    speed: f32,
    facing_obstacle: bool,
}

impl CostContext {
    /// Precomputes goal and line directions from the origin.
    pub fn new(inputs: &CostInputs, is_obstacle_facing_goal: bool) -> Self {
        Self {
            facing_goal: cartesian_to_polar_histogram(&inputs.goal, &inputs.origin),
            goal_distance: (inputs.goal - inputs.origin).norm(),
            facing_line: cartesian_to_polar_histogram(&inputs.closest_pt, &inputs.origin),
            velocity: inputs.velocity,
            speed: inputs.velocity.norm(),
            facing_obstacle: is_obstacle_facing_goal,
        }
    }

    fn yaw_terms(&self, z_deg: f32, k: &CostParams) -> (f32, f32) {
        let w = if self.facing_obstacle { 0.0 } else { 0.5f32 };
        let d_goal = angle_difference(z_deg, self.facing_goal.z_deg);
        let d_line = angle_difference(z_deg, self.facing_line.z_deg);
        (
            (1.0 - w) * k.yaw_cost * d_goal * d_goal,
            w * k.yaw_cost * d_line * d_line,
        )
    }

    fn pitch_term(&self, e_deg: f32, k: &CostParams) -> f32 {
        let de = e_deg - self.facing_goal.e_deg;
        let pitch = k.pitch_cost * de * de;
        if self.goal_distance < 5.0 {
            // The original divides by a double `(0.2 * d)^2` and stores back into a float.
            let s = 0.2 * self.goal_distance as f64;
            (pitch as f64 / (s * s)) as f32
        } else {
            pitch
        }
    }

    fn velocity_term(&self, unit: &Vector3<f32>, k: &CostParams) -> f32 {
        k.velocity_cost * (self.speed - unit.dot(&self.velocity))
    }
}

/// Distance cost of a cell with mean obstacle distance `d_m` (0 = empty): a sigmoid centred at k_obs in (0, 10000).
pub fn distance_cost(d_m: f32, k: &CostParams) -> f32 {
    if d_m > 0.0 {
        let d = k.obstacle_cost_m - d_m;
        5000.0 * (1.0 + d / (1.0 + d * d).sqrt())
    } else {
        0.0
    }
}

/// Cost of one candidate direction (cell centre, r = 1): `(distance_cost, velocity + yaw + yaw_to_line + pitch)`.
pub fn cost_function(candidate: &PolarDeg, obstacle_distance_m: f32, ctx: &CostContext, k: &CostParams) -> (f32, f32) {
    let unit = polar_histogram_to_cartesian(candidate, &Vector3::zeros()).normalize();
    let (yaw, line) = ctx.yaw_terms(candidate.z_deg, k);
    let other = ctx.velocity_term(&unit, k) + yaw + line + ctx.pitch_term(candidate.e_deg, k);
    (distance_cost(obstacle_distance_m, k), other)
}

/// Reusable buffers of [`cost_matrix`].
#[derive(Debug, Clone)]
pub struct CostScratch {
    distance: Vec<f32>,
    smooth: SmoothScratch,
}

impl Default for CostScratch {
    fn default() -> Self {
        Self {
            distance: vec![0.0; GRID_CELLS],
            smooth: SmoothScratch::default(),
        }
    }
}

/// Fills `total` (30 x 60, row-major) with the total cost of every direction from `inputs.origin`.
///
/// Per row the cost function is evaluated only every `step` columns (`step = round(1/cos(elevation))`) and the
/// columns in between are linearly interpolated, including the wrap segment back to column 0. Only the distance
/// part is smoothed (radius `smoothing_radius` cells); total = other + smoothed distance.
#[allow(clippy::too_many_arguments)]
pub fn cost_matrix(
    hist: &Histogram,
    inputs: &CostInputs,
    k: &CostParams,
    smoothing_radius: usize,
    min_range_m: f32,
    max_range_m: f32,
    scratch: &mut CostScratch,
    total: &mut [f32; GRID_CELLS],
) {
    let facing = obstacle_facing_goal(hist, &inputs.goal, &inputs.origin, min_range_m, max_range_m);
    let ctx = CostContext::new(inputs, facing);
    fill_matrices(hist, &ctx, k, total, &mut scratch.distance);
    let dist = &mut scratch.distance;
    smooth_fast(dist, GRID_E, GRID_Z, smoothing_radius, &mut scratch.smooth);
    add_into(total, dist);
}

/// `total += dist`, AVX2-compiled where available (plain additions: same bits).
fn add_into(total: &mut [f32; GRID_CELLS], dist: &[f32]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        unsafe { add_into_avx2(total, dist) };
        return;
    }
    total.iter_mut().zip(dist).for_each(|(o, d)| *o += *d);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn add_into_avx2(total: &mut [f32; GRID_CELLS], dist: &[f32]) {
    total.iter_mut().zip(dist).for_each(|(o, d)| *o += *d);
}

/// Fills the unsmoothed "other" and distance matrices; AVX2-compiled where available (same code: Rust never
/// contracts `a * b + c` into a fused multiply-add, so the results are the same bits).
pub(super) fn fill_matrices(
    hist: &Histogram,
    ctx: &CostContext,
    k: &CostParams,
    other: &mut [f32; GRID_CELLS],
    dist: &mut [f32],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above).
        unsafe { fill_matrices_avx2(hist, ctx, k, other, dist) };
        return;
    }
    fill_matrices_body(hist, ctx, k, other, dist);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn fill_matrices_avx2(
    hist: &Histogram,
    ctx: &CostContext,
    k: &CostParams,
    other: &mut [f32; GRID_CELLS],
    dist: &mut [f32],
) {
    fill_matrices_body(hist, ctx, k, other, dist);
}

/// The per-cell terms in exactly the order of [`cost_function`] (velocity, yaw, line, pitch; the velocity dot
/// product as nalgebra's `(x*x' + y*y') + z*z'`), so each evaluated cell has the same bits.
#[inline(always)]
fn fill_matrices_body(
    hist: &Histogram,
    ctx: &CostContext,
    k: &CostParams,
    other: &mut [f32; GRID_CELLS],
    dist: &mut [f32],
) {
    let t = tables();
    let mut yaw = [0.0f32; GRID_Z];
    let mut line = [0.0f32; GRID_Z];
    for z in 0..GRID_Z {
        (yaw[z], line[z]) = ctx.yaw_terms(index_to_polar(0, z, ALPHA_RES, 1.0).z_deg, k);
    }
    let (vx, vy, vz) = (ctx.velocity.x, ctx.velocity.y, ctx.velocity.z);
    let (kv, speed, k_obs) = (k.velocity_cost, ctx.speed, k.obstacle_cost_m);
    let velocity = |i: usize| kv * (speed - ((t.ux[i] * vx + t.uy[i] * vy) + t.uz[i] * vz));
    // distance_cost as a select, so the loop has no branch.
    let dcost = |h: f32| {
        let d = k_obs - h;
        let c = 5000.0 * (1.0 + d / (1.0 + d * d).sqrt());
        if h > 0.0 { c } else { 0.0 }
    };
    for e in 0..GRID_E {
        let pitch = ctx.pitch_term(index_to_polar(e, 0, ALPHA_RES, 1.0).e_deg, k);
        let step = t.step[e];
        let row = e * GRID_Z;
        let hist_row = &hist.cells()[row..row + GRID_Z];
        let o_row = &mut other[row..row + GRID_Z];
        let d_row = &mut dist[row..row + GRID_Z];
        // Every column is computed (branch-free, vectorised); with a step above 1 the columns between the
        // evaluated ones (every step-th, from 0) are then overwritten by the interpolation, which reads only the
        // evaluated ones: the same bits as computing those alone.
        for z in 0..GRID_Z {
            o_row[z] = velocity(row + z) + yaw[z] + line[z] + pitch;
            d_row[z] = dcost(hist_row[z]);
        }
        if step > 1 {
            interpolate_row(o_row, step);
            // An all-zero row stays all +0 (interpolating +0 gives 0 + 0 * i = +0).
            if d_row.iter().fold(false, |a, &v| a | (v != 0.0)) {
                interpolate_row(d_row, step);
            }
        }
    }
}

/// Fills the columns between the evaluated ones (every `step`-th, from 0) of one row, wrap segment included.
/// The common steps get a compile-time segment length so the inner loop unrolls; same arithmetic.
#[inline(always)]
fn interpolate_row(row: &mut [f32], step: usize) {
    match step {
        2 => interpolate_segments::<2>(row),
        3 => interpolate_segments::<3>(row),
        4 => interpolate_segments::<4>(row),
        6 => interpolate_segments::<6>(row),
        _ => {
            let mut last = 0;
            let mut z = step;
            while z < GRID_Z {
                interpolate(row, last, z, step);
                last = z;
                z += step;
            }
            interpolate_wrap(row, last);
        }
    }
}

#[inline(always)]
fn interpolate_segments<const STEP: usize>(row: &mut [f32]) {
    let mut last = 0;
    let mut z = STEP;
    while z < GRID_Z {
        let grad = (row[z] - row[last]) / STEP as f32;
        for i in 1..STEP {
            row[last + i] = row[last] + grad * i as f32;
        }
        last = z;
        z += STEP;
    }
    interpolate_wrap(row, last);
}

/// Fills `row[last+1 .. next)` on the straight line between `row[last]` and `row[next]`.
#[inline(always)]
fn interpolate(row: &mut [f32], last: usize, next: usize, step: usize) {
    let grad = (row[next] - row[last]) / step as f32;
    for i in 1..step {
        row[last + i] = row[last] + grad * i as f32;
    }
}

/// Fills the wrap segment after `last` towards column 0 (length `60 - last`).
#[inline(always)]
fn interpolate_wrap(row: &mut [f32], last: usize) {
    let span = GRID_Z - last;
    let grad = (row[0] - row[last]) / span as f32;
    for i in 1..span {
        row[last + i] = row[last] + grad * i as f32;
    }
}

/// A candidate direction: total cost and the cell-centre angles (histogram polar, degrees).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// Total cost (lower is better).
    pub cost: f32,
    /// Cell-centre elevation, degrees, positive up.
    pub e_deg: f32,
    /// Cell-centre azimuth, degrees clockwise from North.
    pub z_deg: f32,
}

/// Integer key ordered exactly like [`f32::total_cmp`] (the standard library's own bit trick).
#[inline(always)]
pub(super) fn total_key(c: f32) -> i32 {
    let b = c.to_bits() as i32;
    b ^ (((b >> 31) as u32) >> 1) as i32
}

/// The `n` smallest `(key, index)` pairs seen so far, ascending; `offer` order does not matter.
pub(super) struct TopN {
    n: usize,
    kept: Vec<(i32, u32)>,
}

impl TopN {
    /// Keeps the `n` smallest (n >= 1).
    pub(super) fn new(n: usize) -> Self {
        Self {
            n,
            kept: Vec::with_capacity(n + 1),
        }
    }

    /// The kept `(key, index)` pairs, ascending.
    pub(super) fn kept(&self) -> &[(i32, u32)] {
        &self.kept
    }

    /// The worst kept key once `n` are kept (a cell with a larger key cannot enter).
    #[inline(always)]
    pub(super) fn bound(&self) -> i32 {
        if self.kept.len() == self.n {
            self.kept[self.n - 1].0
        } else {
            i32::MAX
        }
    }

    /// Offers the cells `totals` (indices from `first_index` on) in chunks of 16, skipping a chunk none of whose
    /// keys can enter: the scan order, and so the tie-breaking, is that of offering every cell in turn.
    #[inline]
    pub(super) fn offer_cells(&mut self, totals: &[f32], first_index: usize) {
        const CHUNK: usize = 16;
        for (ci, chunk) in totals.chunks(CHUNK).enumerate() {
            let bound = self.bound();
            if !chunk.iter().fold(false, |a, &t| a | (total_key(t) <= bound)) {
                continue;
            }
            for (j, &t) in chunk.iter().enumerate() {
                let key = total_key(t);
                if key <= self.bound() {
                    self.offer(key, (first_index + ci * CHUNK + j) as u32);
                }
            }
        }
    }

    #[inline]
    pub(super) fn offer(&mut self, key: i32, index: u32) {
        let item = (key, index);
        if self.kept.len() == self.n {
            if item >= self.kept[self.n - 1] {
                return;
            }
            self.kept.pop();
        }
        let mut at = self.kept.len();
        while at > 0 && self.kept[at - 1] > item {
            at -= 1;
        }
        self.kept.insert(at, item);
    }
}

/// The `n` cheapest cells sorted by ascending cost. Scan order is row-major; ties keep the earlier cell
/// (a deterministic version of the original's max-heap, which replaces its worst only when strictly cheaper).
///
/// Equal to sorting all cells by `(cost.total_cmp, index)` and keeping the first `n` (checked against
/// `reference::best_candidates`). The row with the smallest cost is scanned first; afterwards whole rows whose
/// minimum exceeds the worst kept cost, and chunks none of whose cells reaches it, are skipped.
pub fn best_candidates(total: &[f32; GRID_CELLS], n: usize, out: &mut Vec<Candidate>) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above); the body is the same integer code.
        unsafe { best_candidates_avx2(total, n, out) };
        return;
    }
    best_candidates_body(total, n, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn best_candidates_avx2(total: &[f32; GRID_CELLS], n: usize, out: &mut Vec<Candidate>) {
    best_candidates_body(total, n, out);
}

#[inline(always)]
fn best_candidates_body(total: &[f32; GRID_CELLS], n: usize, out: &mut Vec<Candidate>) {
    out.clear();
    if n == 0 {
        return;
    }
    let mut top = TopN {
        n: n.min(GRID_CELLS),
        kept: Vec::with_capacity(n.min(GRID_CELLS) + 1),
    };
    // Keys are recomputed on the fly (3 integer ops) rather than stored: no 7 kB buffer to fill.
    let mut row_min = [i32::MAX; GRID_E];
    for (m, row) in row_min.iter_mut().zip(total.chunks_exact(GRID_Z)) {
        *m = row.iter().fold(i32::MAX, |a, &c| a.min(total_key(c)));
    }
    let first = (0..GRID_E).min_by_key(|&r| row_min[r]).unwrap_or(0);
    let rows = std::iter::once(first).chain((0..GRID_E).filter(|&r| r != first));
    for r in rows {
        if row_min[r] > top.bound() {
            continue;
        }
        let base = r * GRID_Z;
        top.offer_cells(&total[base..base + GRID_Z], base);
    }
    out.extend(top.kept.iter().map(|&(_, i)| {
        let i = i as usize;
        let p = index_to_polar(i / GRID_Z, i % GRID_Z, ALPHA_RES, 1.0);
        Candidate {
            cost: total[i],
            e_deg: p.e_deg,
            z_deg: p.z_deg,
        }
    }));
}

#[cfg(test)]
#[path = "cost_tests.rs"]
mod tests;
