//! The original's data-driven camera FOV (docs/planner.md §3.4): each cloud's six extreme points (min/max x, y, z in
//! the camera's optical frame, AV `removeNaNAndGetMaxima`) are turned into body-frame FCU polar, and their
//! angular spread widens the FOV, which never shrinks (AV `updateFOVFromMaxima`, run by the nodelet's cloud
//! transform thread before the planner sees the cloud). It starts at zero (AV `FOV()`).
//!
//! Frames: the planner receives ENU points; the body frame is FLU (x forward, y left, z up), optical is x right,
//! y down, z forward (the zero-translation `fcu -> camera_link` transform of the launch file), FCU polar has the
//! azimuth counter-clockwise from forward and the elevation positive **below** the horizon.

use nalgebra::Vector3;

use super::fov::Fov;
use super::polar::{cartesian_to_polar_fcu, wrap_180};

/// Where the planner's camera FOV comes from.
///
/// Measured on the 127 recorded flights with obstacles (`fidelity tests/data/hfs-flights --cv 5
/// [--motion px4] --fov-estimate fixed|maxima`), Fixed -> FromMaxima, cross-validated (= in-sample: every fold
/// chose the shipped constants): paper MAE 0.478 -> 0.484 m, Spearman 0.798 -> 0.805, recall < 1.5 m
/// 0.500 -> 0.483; px4 MAE 0.552 -> 0.550 m, Spearman 0.751 -> 0.752, recall 0.379 both; precision 1.000 in
/// all four. Leave-one-tier-out, paper tier C 0.510 -> 0.671 m (its training tiers then chose 3 m/s, 13.5
/// deg/s, no delay). `--ensemble 8` (in-sample): p_fail AUC 0.882 -> 0.854, Brier 0.142 -> 0.154. Predictions
/// move 0.069 m on average (at most 0.655 m); the paired change of |error| is +0.005 m +- 0.010 (standard
/// error). No figure improves beyond noise and p_fail gets worse, so `Fixed` stays the default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FovEstimate {
    /// The pinhole span of the camera's extreme pixel centres, fixed for the flight ([`Fov::from_pinhole`]).
    #[default]
    Fixed,
    /// As the original: zero at start, widened by every frame's extreme points, never narrowed. The LFS feeds
    /// it its planner frame (the first pixel of each 2-degree cell within the 15 m sensor range), not every
    /// pixel up to the 18 m far clip: after a ground-only takeoff that gives 58.9 x 21.2 deg centred 11.4 deg
    /// below the horizon where the full render gives 58.9 x 19.5 centred 10.5
    /// (tested in the simulator's `fov_takeoff_tests`).
    FromMaxima,
}

impl FovEstimate {
    /// The setting by CLI name (`fixed` or `maxima`).
    pub fn by_name(name: &str) -> Option<Self> {
        match name {
            "fixed" => Some(Self::Fixed),
            "maxima" => Some(Self::FromMaxima),
            _ => None,
        }
    }
}

/// The vehicle pose the cloud was seen from: the body origin (ENU metres), ENU yaw and pitch (radians,
/// positive nose-down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPose {
    /// Body origin, ENU metres.
    pub position_enu: Vector3<f32>,
    /// ENU yaw, radians counter-clockwise from East.
    pub yaw_enu_rad: f32,
    /// Pitch, radians, positive nose-down.
    pub pitch_rad: f32,
}

impl BodyPose {
    /// The body-frame (FLU) offset of ENU point `p`: undo the yaw about up, then the nose-down pitch about the
    /// body's y axis.
    pub fn body_flu(&self, p: &Vector3<f32>) -> Vector3<f32> {
        let d = p - self.position_enu;
        let (sy, cy) = self.yaw_enu_rad.sin_cos();
        let (lx, ly, lz) = (cy * d.x + sy * d.y, -sy * d.x + cy * d.y, d.z);
        let (sp, cp) = self.pitch_rad.sin_cos();
        Vector3::new(cp * lx - sp * lz, ly, sp * lx + cp * lz)
    }
}

/// Optical-frame (x right, y down, z forward) coordinates of a body FLU vector.
pub fn optical_from_body(b: &Vector3<f32>) -> Vector3<f32> {
    Vector3::new(-b.y, -b.z, b.x)
}

/// Indices into `optical` of the points with max x, y, z and min x, y, z (finite points only; the first of
/// equal values wins, as the original's strict comparisons). Empty if no point is finite.
pub fn maxima_indices(optical: &[Vector3<f32>]) -> Vec<usize> {
    // Index of the running extreme per (axis, is_max); the original starts from +-9999 m, far beyond any cloud.
    let mut best: [Option<(usize, f32)>; 6] = [None; 6];
    for (i, p) in optical.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            continue;
        }
        for axis in 0..3 {
            let v = p[axis];
            if best[axis].is_none_or(|(_, b)| v > b) {
                best[axis] = Some((i, v));
            }
            if best[axis + 3].is_none_or(|(_, b)| v < b) {
                best[axis + 3] = Some((i, v));
            }
        }
    }
    best.iter().flatten().map(|&(i, _)| i).collect()
}

/// Widens `fov` to the angular spread of `maxima_body` (body FLU points) where that spread is larger, per axis
/// independently; the centre moves only with its axis' span. Nothing happens without points.
pub fn grow_from_maxima(fov: &mut Fov, maxima_body: &[Vector3<f32>]) {
    if maxima_body.is_empty() {
        return;
    }
    let (mut h_min, mut h_max, mut v_min, mut v_max) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
    for p in maxima_body {
        let pol = cartesian_to_polar_fcu(p, &Vector3::zeros());
        // Shifted to [0, 360] and [0, 180] so the spans are differences of non-negative angles.
        let (h, v) = (pol.z_deg + 180.0, pol.e_deg + 90.0);
        h_min = h_min.min(h);
        h_max = h_max.max(h);
        v_min = v_min.min(v);
        v_max = v_max.max(v);
    }
    let h_diff = (h_max - h_min).min(360.0 - h_max + h_min);
    let v_diff = (v_max - v_min).min(360.0 - v_max + v_min);
    if h_diff > fov.h_fov_deg {
        fov.h_fov_deg = h_diff;
        // The original assumes one camera sees less than 180 degrees: the shorter way round is the camera.
        fov.yaw_deg = if h_diff >= h_max - h_min {
            wrap_180((h_max + h_min) / 2.0 - 180.0)
        } else {
            wrap_180((h_max + h_min) / 2.0)
        };
    }
    if v_diff > fov.v_fov_deg {
        fov.v_fov_deg = v_diff;
        fov.pitch_deg = (v_max + v_min) / 2.0 - 90.0;
    }
}

/// One frame's update: the extreme points of `points_enu` (as seen from `pose`) widen `fov`. `scratch` holds
/// the optical-frame copy between calls.
pub fn update_from_cloud(fov: &mut Fov, points_enu: &[Vector3<f32>], pose: &BodyPose, scratch: &mut Vec<Vector3<f32>>) {
    scratch.clear();
    scratch.extend(points_enu.iter().map(|p| optical_from_body(&pose.body_flu(p))));
    let maxima: Vec<Vector3<f32>> = maxima_indices(scratch)
        .into_iter()
        .map(|i| pose.body_flu(&points_enu[i]))
        .collect();
    grow_from_maxima(fov, &maxima);
}

#[cfg(test)]
#[path = "fov_estimate_tests.rs"]
mod tests;
