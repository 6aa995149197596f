//! The star planner's look-ahead tree (docs/planner.md §6, AV `StarPlanner::buildLookAheadTree`): rebuilt from scratch
//! every iteration; each expansion builds a histogram at the node from the whole memory cloud, takes the 8 best
//! directions and adds 2 m children; the path ends at the deepest open node.
//!
//! Positions and velocities are ENU metres (m/s at the root, a 2 m edge vector at other nodes).

use nalgebra::Vector3;

use super::cloud::PointMemory;
use super::cost::{Candidate, CostInputs};
use super::histogram::{Histogram, HistogramScratch};
use super::params::PlannerParams;
use super::polar::{PolarDeg, polar_histogram_to_cartesian};
use super::select::{SelectScratch, best_candidates_lazy};

/// A node of the tree. Index 0 is the root (the vehicle at planning time).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeNode {
    /// Node position, ENU metres.
    pub position_enu: Vector3<f32>,
    /// Vehicle velocity at the root (m/s); the edge vector from the parent elsewhere (m).
    pub velocity_enu: Vector3<f32>,
    /// Index of the parent node (0 for the root itself).
    pub parent: usize,
    /// Accumulated candidate costs plus heuristic.
    pub total_cost: f32,
    /// `tree_heuristic_weight * |goal - position|`.
    pub heuristic: f32,
    /// Number of edges from the root.
    pub depth: u32,
    /// True once expanded.
    pub closed: bool,
}

/// Smallest f32 `t` with `sqrt(t) >= limit`, so `sqrt(s) < limit` exactly when `s < t` (no sqrt in hot loops).
fn sqrt_threshold(limit: f32) -> f32 {
    let mut t = limit * limit;
    while t > 0.0 && t.sqrt() >= limit {
        t = t.next_down();
    }
    while t.sqrt() < limit {
        t = t.next_up();
    }
    t
}

/// Two nodes closer than this (m, hard-coded in the original) are the same node.
const CLOSE_NODE_M: f32 = 0.2;

/// Builds look-ahead trees, reusing its buffers between calls.
#[derive(Debug, Clone, Default)]
pub struct StarPlanner {
    nodes: Vec<TreeNode>,
    // Node positions again as parallel arrays for the vectorised close-node test.
    nx: Vec<f32>,
    ny: Vec<f32>,
    nz: Vec<f32>,
    path: Vec<Vector3<f32>>,
    expanded: usize,
    hist: Histogram,
    hist_scratch: HistogramScratch,
    select_scratch: SelectScratch,
    candidates: Vec<Candidate>,
}

/// What the tree is built for (ENU).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreeInputs {
    /// Vehicle position (root), metres.
    pub position: Vector3<f32>,
    /// Vehicle velocity at the root, m/s.
    pub velocity: Vector3<f32>,
    /// Goal, metres.
    pub goal: Vector3<f32>,
    /// Closest point on the previous-goal-to-goal line, metres.
    pub closest_pt: Vector3<f32>,
}

impl StarPlanner {
    /// A planner with empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// All nodes of the last tree (index 0 = root).
    pub fn nodes(&self) -> &[TreeNode] {
        &self.nodes
    }

    /// Path of the last tree: **index 0 = deepest node, last = root**; element `len - 2` is the depth-1 node.
    pub fn path(&self) -> &[Vector3<f32>] {
        &self.path
    }

    /// Number of expansions done by the last build.
    pub fn expanded(&self) -> usize {
        self.expanded
    }

    fn heuristic(&self, p: &Vector3<f32>, goal: &Vector3<f32>, params: &PlannerParams) -> f32 {
        (goal - p).norm() * params.tree_heuristic_weight
    }

    fn push(&mut self, node: TreeNode) {
        self.nx.push(node.position_enu.x);
        self.ny.push(node.position_enu.y);
        self.nz.push(node.position_enu.z);
        self.nodes.push(node);
    }

    /// Is any node within 0.2 m of `p`? Branch-free chunks so the compiler vectorises the distance test.
    fn has_close_node(&self, p: &Vector3<f32>, threshold2: f32) -> bool {
        const CHUNK: usize = 32;
        let n = self.nx.len();
        let mut start = 0;
        while start < n {
            let end = (start + CHUNK).min(n);
            let hit = self.nx[start..end]
                .iter()
                .zip(&self.ny[start..end])
                .zip(&self.nz[start..end])
                .fold(false, |acc, ((x, y), z)| {
                    let (dx, dy, dz) = (x - p.x, y - p.y, z - p.z);
                    acc | (dx * dx + dy * dy + dz * dz < threshold2)
                });
            if hit {
                return true;
            }
            start = end;
        }
        false
    }

    /// Rebuilds the tree from the processed cloud and returns the path (deepest node first, root last).
    pub fn build(&mut self, cloud: &PointMemory, inputs: &TreeInputs, params: &PlannerParams) -> &[Vector3<f32>] {
        self.build_with_root_histogram(cloud, inputs, params, None)
    }

    /// [`Self::build`] reusing `root_hist`, the histogram of `cloud` at `inputs.position` that the caller has
    /// already built (the planner builds it to decide whether to plan), instead of building it again for the
    /// root expansion. Passing a histogram of anything else changes the tree.
    pub fn build_with_root_histogram(
        &mut self,
        cloud: &PointMemory,
        inputs: &TreeInputs,
        params: &PlannerParams,
        root_hist: Option<&Histogram>,
    ) -> &[Vector3<f32>] {
        self.reset(inputs, params);
        let close2 = sqrt_threshold(CLOSE_NODE_M);
        let radius2 = sqrt_threshold(params.max_sensor_range_m);
        let mut origin = 0;
        for _ in 0..params.n_expanded_nodes {
            // The root (index 0) is expanded first and only once.
            let root_hist = root_hist.filter(|_| origin == 0);
            self.expand(origin, cloud, root_hist, inputs, params, close2);
            match self.cheapest_open_within(&inputs.position, radius2) {
                Some(i) => origin = i,
                None => break,
            }
        }
        self.trace_deepest()
    }

    /// Empties the tree down to its root at the vehicle.
    fn reset(&mut self, inputs: &TreeInputs, params: &PlannerParams) {
        self.nodes.clear();
        self.nx.clear();
        self.ny.clear();
        self.nz.clear();
        self.expanded = 0;
        let h0 = self.heuristic(&inputs.position, &inputs.goal, params);
        self.push(TreeNode {
            position_enu: inputs.position,
            velocity_enu: inputs.velocity,
            parent: 0,
            total_cost: h0,
            heuristic: h0,
            depth: 0,
            closed: false,
        });
    }

    /// Expands node `origin`: its cheapest directions (from `root_hist` if given, else from the histogram of
    /// `cloud` at the node) become children unless a node is already within `close2` (squared metres).
    fn expand(
        &mut self,
        origin: usize,
        cloud: &PointMemory,
        root_hist: Option<&Histogram>,
        inputs: &TreeInputs,
        params: &PlannerParams,
        close2: f32,
    ) {
        let o = self.nodes[origin];
        let hist = match root_hist {
            Some(h) => h,
            None => {
                let (xs, ys, zs) = cloud.soa();
                self.hist
                    .build_from_soa(xs, ys, zs, &o.position_enu, &mut self.hist_scratch);
                &self.hist
            }
        };
        let cost_inputs = CostInputs {
            goal: inputs.goal,
            origin: o.position_enu,
            velocity: o.velocity_enu,
            closest_pt: inputs.closest_pt,
        };
        let mut candidates = std::mem::take(&mut self.candidates);
        best_candidates_lazy(
            hist,
            &cost_inputs,
            &params.cost,
            params.smoothing_radius(),
            params.min_sensor_range_m,
            params.max_sensor_range_m,
            params.children_per_node,
            &mut self.select_scratch,
            &mut candidates,
        );
        if candidates.is_empty() {
            self.nodes[origin].total_cost = f32::INFINITY;
        }
        for c in &candidates {
            let polar = PolarDeg::new(c.e_deg, c.z_deg, params.tree_node_distance_m);
            let location = polar_histogram_to_cartesian(&polar, &o.position_enu);
            if self.has_close_node(&location, close2) {
                continue;
            }
            let h = self.heuristic(&location, &inputs.goal, params);
            self.push(TreeNode {
                position_enu: location,
                velocity_enu: location - o.position_enu,
                parent: origin,
                total_cost: o.total_cost - o.heuristic + c.cost + h,
                heuristic: h,
                depth: o.depth + 1,
                closed: false,
            });
        }
        self.candidates = candidates;
        self.nodes[origin].closed = true;
        self.expanded += 1;
    }

    /// The cheapest open node closer than `sqrt(radius2)` to the vehicle at `position` (lowest index on ties).
    fn cheapest_open_within(&self, position: &Vector3<f32>, radius2: f32) -> Option<usize> {
        let mut best: Option<(usize, f32)> = None;
        for (i, n) in self.nodes.iter().enumerate() {
            if n.closed {
                continue;
            }
            let within = (n.position_enu - position).norm_squared() < radius2;
            if within && n.total_cost < best.map_or(f32::INFINITY, |b| b.1) {
                best = Some((i, n.total_cost));
            }
        }
        best.map(|b| b.0)
    }

    /// The path from the deepest open node (strict >, so the lowest index wins ties; the root if none is
    /// deeper than 0) back to the root.
    fn trace_deepest(&mut self) -> &[Vector3<f32>] {
        let mut end = 0;
        let mut max_depth = 0;
        for (i, n) in self.nodes.iter().enumerate() {
            if !n.closed && n.depth > max_depth {
                max_depth = n.depth;
                end = i;
            }
        }
        self.path.clear();
        while end > 0 {
            self.path.push(self.nodes[end].position_enu);
            end = self.nodes[end].parent;
        }
        self.path.push(self.nodes[0].position_enu);
        &self.path
    }
}

#[cfg(test)]
#[path = "tree_tests.rs"]
mod tests;
