//! The cost matrix of 3DVFH* (3dvfh.md §5, AV `getCostMatrix` / `costFunction` /
//! `getBestCandidatesFromCostMatrix`): per direction, a distance cost from the histogram (smoothed) plus velocity,
//! yaw, yaw-to-line and pitch costs (not smoothed). Lower is better.
//!
//! Matrices are row-major `(e, z)` 30 x 60 like the histogram. Positions and velocities are ENU.

use std::sync::OnceLock;

use nalgebra::Vector3;

use super::histogram::Histogram;
use super::params::CostParams;
use super::polar::{
    ALPHA_RES, DEG_TO_RAD, GRID_CELLS, GRID_E, GRID_Z, PolarDeg, angle_difference, cartesian_to_polar_histogram,
    index_to_polar, polar_histogram_to_cartesian, polar_to_index,
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
    /// Closest point on the previous-goal-to-goal line (3dvfh.md §7.3), or the goal.
    pub closest_pt: Vector3<f32>,
}

/// Geometry shared by every cost matrix: cell-centre directions and the azimuth step of each row.
struct CellTables {
    /// Normalised unit vector of each cell centre (ENU), as `polarHistogramToCartesian(.., r = 1).normalized()`.
    unit: Vec<Vector3<f32>>,
    /// Azimuth step per row: `round(1 / cos(row centre elevation))`.
    step: [usize; GRID_E],
}

fn tables() -> &'static CellTables {
    static TABLES: OnceLock<CellTables> = OnceLock::new();
    TABLES.get_or_init(|| {
        let mut unit = Vec::with_capacity(GRID_CELLS);
        for e in 0..GRID_E {
            for z in 0..GRID_Z {
                let v = polar_histogram_to_cartesian(&index_to_polar(e, z, ALPHA_RES, 1.0), &Vector3::zeros());
                unit.push(v.normalize());
            }
        }
        let mut step = [1; GRID_E];
        for (e, s) in step.iter_mut().enumerate() {
            let bin_width = (index_to_polar(e, 0, ALPHA_RES, 1.0).e_deg * DEG_TO_RAD).cos();
            *s = (1.0 / bin_width).round() as usize;
        }
        CellTables { unit, step }
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
    let t = tables();
    let facing = obstacle_facing_goal(hist, &inputs.goal, &inputs.origin, min_range_m, max_range_m);
    let ctx = CostContext::new(inputs, facing);
    let mut yaw = [0.0f32; GRID_Z];
    let mut line = [0.0f32; GRID_Z];
    for z in 0..GRID_Z {
        (yaw[z], line[z]) = ctx.yaw_terms(index_to_polar(0, z, ALPHA_RES, 1.0).z_deg, k);
    }
    let other = total;
    let dist = &mut scratch.distance;
    for e in 0..GRID_E {
        let pitch = ctx.pitch_term(index_to_polar(e, 0, ALPHA_RES, 1.0).e_deg, k);
        let step = t.step[e];
        let row = e * GRID_Z;
        let hist_row = &hist.cells()[row..row + GRID_Z];
        let units = &t.unit[row..row + GRID_Z];
        if step == 1 {
            let o = &mut other[row..row + GRID_Z];
            for (((((o, u), y), l), d), h) in o
                .iter_mut()
                .zip(units)
                .zip(&yaw)
                .zip(&line)
                .zip(&mut dist[row..row + GRID_Z])
                .zip(hist_row)
            {
                *o = ctx.velocity_term(u, k) + y + l + pitch;
                *d = distance_cost(*h, k);
            }
        } else {
            for z in (0..GRID_Z).step_by(step) {
                other[row + z] = ctx.velocity_term(&units[z], k) + yaw[z] + line[z] + pitch;
                dist[row + z] = distance_cost(hist_row[z], k);
            }
        }
        if step > 1 {
            let mut last = 0;
            let mut z = step;
            while z < GRID_Z {
                interpolate(&mut other[row..row + GRID_Z], last, z, step);
                interpolate(&mut dist[row..row + GRID_Z], last, z, step);
                last = z;
                z += step;
            }
            interpolate_wrap(&mut other[row..row + GRID_Z], last);
            interpolate_wrap(&mut dist[row..row + GRID_Z], last);
        }
    }
    smooth_fast(dist, GRID_E, GRID_Z, smoothing_radius, &mut scratch.smooth);
    for (o, d) in other.iter_mut().zip(dist.iter()) {
        *o += *d;
    }
}

/// Fills `row[last+1 .. next)` on the straight line between `row[last]` and `row[next]`.
fn interpolate(row: &mut [f32], last: usize, next: usize, step: usize) {
    let grad = (row[next] - row[last]) / step as f32;
    for i in 1..step {
        row[last + i] = row[last] + grad * i as f32;
    }
}

/// Fills the wrap segment after `last` towards column 0 (length `60 - last`).
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

/// The `n` cheapest cells sorted by ascending cost. Scan order is row-major; ties keep the earlier cell
/// (a deterministic version of the original's max-heap, which replaces its worst only when strictly cheaper).
pub fn best_candidates(total: &[f32; GRID_CELLS], n: usize, out: &mut Vec<Candidate>) {
    out.clear();
    if n == 0 {
        return;
    }
    // Every cell of the n cheapest costs at most the n-th smallest row minimum (n distinct rows hold cells that
    // cheap), so only cells up to that threshold need sorting. Sorting by (cost, index) is exact, ties included.
    let mut row_min = [f32::INFINITY; GRID_E];
    for (m, row) in row_min.iter_mut().zip(total.chunks_exact(GRID_Z)) {
        *m = row.iter().fold(f32::INFINITY, |a, &b| a.min(b));
    }
    let threshold = if n <= GRID_E {
        row_min.sort_unstable_by(f32::total_cmp);
        row_min[n - 1]
    } else {
        f32::INFINITY
    };
    let mut best: Vec<(f32, usize)> = total
        .iter()
        .enumerate()
        .filter(|&(_, &c)| c <= threshold)
        .map(|(i, &c)| (c, i))
        .collect();
    best.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    best.truncate(n);
    out.extend(best.iter().map(|&(cost, i)| {
        let p = index_to_polar(i / GRID_Z, i % GRID_Z, ALPHA_RES, 1.0);
        Candidate {
            cost,
            e_deg: p.e_deg,
            z_deg: p.z_deg,
        }
    }));
}

#[cfg(test)]
#[path = "cost_tests.rs"]
mod tests;
