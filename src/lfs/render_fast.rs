//! The planner cycle's render: only the pixels the 2-degree subsampling (docs/planner.md §3.2) would keep.
//!
//! The cloud processing keeps, of each 2-degree cell seen from the vehicle, the **first** valid point in pixel
//! (row-major) order. Because the pipeline transforms the cloud with a zero-translation extrinsic, a pixel's
//! point lies along its own ray direction from the body origin, so its cell depends only on the pixel, not on
//! its depth. For a level camera every column is a vertical plane; in it, each box (a rectangle in
//! horizontal-distance x height) and the ground (a line) are hit within the valid depth and range limits for
//! one interval of ray slopes, computed in closed form. "Valid" is "some surface is hit within the limits"
//! (the nearest hit is then too), so the first valid row of every (column, elevation band) follows without
//! casting, and only the chosen pixels are ray cast with parry3d. The result equals the full render followed
//! by subsampling (tested below); pitched poses or a box within the near clip fall back to the full render.

use nalgebra::Vector3;

use super::camera::Camera;
use super::column_slopes::{box_slopes, ground_slopes};
use super::render::{CameraPose, RenderError, Scene, cloud_from_depth, pixel_point_enu_tans, render_depth};
use prgenuav_planner::histogram::azimuth_cell;

const SUB_RES_DEG: i32 = 2;
const SUB_E: usize = 90;
const SUB_Z: usize = 180;
/// Angles this close to a 2-degree edge (degrees) are treated as on either side: 4x the worst rounding of the
/// planner's f32 point-to-angle path.
const EDGE_EPS_DEG: f64 = 2e-3;
/// Row positions this close to an integer (pixels) are treated as on either side (parry casts in f32).
const ROW_EPS: f64 = 0.01;

/// Exactly `x.floor()` (sign of zero included) without the libm call that baseline x86-64 needs (no rounding
/// instruction); it is the render's most frequent call.
#[inline]
fn floor_f64(x: f64) -> f64 {
    if x.abs() < 4_503_599_627_370_496.0 {
        let t = x as i64 as f64;
        if t > x { t - 1.0 } else { t.copysign(x) }
    } else {
        x
    }
}

fn near_edge(angle_deg: f64) -> bool {
    let u = angle_deg / f64::from(SUB_RES_DEG);
    (u - u.round()).abs() * f64::from(SUB_RES_DEG) < EDGE_EPS_DEG
}

/// The range window (metres from the body origin) in which the planner keeps new points (strict both sides).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeepRange {
    /// Lower bound (`min_sensor_range`, 0.2 m).
    pub min_m: f32,
    /// Upper bound (`max_sensor_range`, 15 m).
    pub max_m: f32,
}

/// Reusable buffers of [`render_cloud`].
#[derive(Debug, Clone)]
pub struct FastRenderScratch {
    first: Vec<u32>,
    stamp: Vec<u32>,
    generation: u32,
    touched: Vec<usize>,
    keys: Vec<u32>,
    extras: Vec<u32>,
    tan_x: Vec<f64>,
    tan_y: Vec<f64>,
    tan_band: Vec<f64>,
    camera: Option<Camera>,
    /// Frames rendered in full because the fast path did not apply.
    pub fallbacks: u64,
}

impl Default for FastRenderScratch {
    fn default() -> Self {
        Self {
            first: vec![0; SUB_E * SUB_Z],
            stamp: vec![0; SUB_E * SUB_Z],
            generation: 0,
            touched: Vec::new(),
            keys: Vec::new(),
            extras: Vec::new(),
            tan_x: Vec::new(),
            tan_y: Vec::new(),
            tan_band: (0..=SUB_E)
                .map(|k| ((k as f64 * 2.0 - 90.0).to_radians()).tan())
                .collect(),
            camera: None,
            fallbacks: 0,
        }
    }
}

impl FastRenderScratch {
    fn prepare(&mut self, camera: &Camera) {
        if self.camera.as_ref() != Some(camera) {
            self.tan_x = (0..camera.width_px).map(|i| camera.tan_x(i)).collect();
            self.tan_y = (0..camera.height_px).map(|j| camera.tan_y(j)).collect();
            self.camera = Some(camera.clone());
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
        self.touched.clear();
        self.keys.clear();
        self.extras.clear();
    }

    fn offer(&mut self, cell: usize, key: u32) {
        if self.stamp[cell] != self.generation {
            self.stamp[cell] = self.generation;
            self.first[cell] = key;
            self.touched.push(cell);
        } else if key < self.first[cell] {
            self.first[cell] = key;
        }
    }
}

/// Appends to `out` (ENU, planner frame, pixel order) a cloud that the 2-degree subsampling turns into exactly
/// the same processed cloud as the full render's: for every 2-degree cell, its first valid pixel.
pub fn render_cloud(
    scene: &Scene,
    camera: &Camera,
    pose: &CameraPose,
    keep: KeepRange,
    scratch: &mut FastRenderScratch,
    out: &mut Vec<Vector3<f32>>,
) -> Result<(), RenderError> {
    scene.check_pose(camera, pose)?;
    let cam = pose.camera_position(camera);
    let corner = camera.ray_body(0, 0).norm();
    let margin = f64::from(camera.near_clip_m) * corner + 0.05;
    let close_box = scene.boxes.iter().any(|b| b.distance(&cam) < margin);
    let limit_lo = camera.near_clip_m.max(camera.cutoff_min_m);
    if pose.pitch_rad.abs() > 1e-9 || close_box || keep.min_m > limit_lo {
        scratch.fallbacks += 1;
        let img = render_depth(scene, camera, pose)?;
        out.extend(cloud_from_depth(camera, pose, &img));
        return Ok(());
    }
    scratch.prepare(camera);
    let (sy, cyaw) = pose.yaw_enu_rad.sin_cos();
    let frame = LevelFrame {
        scene,
        cam,
        w: camera.width_px,
        h: camera.height_px,
        fl: camera.focal_px(),
        cy: camera.center_px().1,
        sy,
        cyaw,
        depth_lo: f64::from(limit_lo),
        depth_hi: f64::from(camera.far_clip_m.min(camera.cutoff_max_m)),
        range_hi: f64::from(keep.max_m),
    };
    let mut intervals: Vec<(f64, f64)> = Vec::with_capacity(scene.boxes.len() + 1);
    for i in 0..frame.w {
        frame.scan_column(i, &mut intervals, scratch);
    }
    cast_chosen(&frame, camera, pose, scratch, out);
    Ok(())
}

/// A level frame's constants for the column scan: the scene, the camera's ENU position (metres), the image size
/// and focal length (pixels), its centre row, the yaw's sine and cosine, and the depth and range limits (metres).
struct LevelFrame<'a> {
    scene: &'a Scene,
    cam: Vector3<f64>,
    w: u32,
    h: u32,
    fl: f64,
    cy: f64,
    sy: f64,
    cyaw: f64,
    depth_lo: f64,
    depth_hi: f64,
    range_hi: f64,
}

impl LevelFrame<'_> {
    /// Offers (or marks for casting) the first row of every elevation band of pixel column `i`.
    fn scan_column(&self, i: u32, intervals: &mut Vec<(f64, f64)>, scratch: &mut FastRenderScratch) {
        let tx = scratch.tan_x[i as usize];
        // Column direction: body (1, -tx) turned by yaw; n = horizontal metres per metre of depth.
        let (bx, by) = (1.0, -tx);
        let (ux, uy) = (self.cyaw * bx - self.sy * by, self.sy * bx + self.cyaw * by);
        let n = (1.0 + tx * tx).sqrt();
        self.column_intervals(ux, uy, n, intervals);
        if intervals.is_empty() {
            return;
        }
        let tan_y = std::mem::take(&mut scratch.tan_y);
        let tan_band = std::mem::take(&mut scratch.tan_band);
        let column = Column {
            i,
            w: self.w,
            h: self.h,
            cy: self.cy,
            scale: self.fl * n,
            inv_n: 1.0 / n,
            z_idx: azimuth_cell(ux as f32, uy as f32, SUB_RES_DEG),
            // A column this close to an azimuth cell edge may fall on either side once its points are rounded.
            az_ambiguous: near_edge(ux.atan2(uy).to_degrees()),
            tan_y: &tan_y,
            tan_band: &tan_band,
        };
        for &(s_lo, s_hi) in intervals.iter() {
            column.scan_interval(s_lo, s_hi, scratch);
        }
        scratch.tan_band = tan_band;
        scratch.tan_y = tan_y;
    }

    /// The slope intervals of the column in horizontal direction `(ux, uy)` (`n` horizontal metres per metre of
    /// depth) in which the ground or a box is hit within the limits, keeping those that reach the image's rows.
    fn column_intervals(&self, ux: f64, uy: f64, n: f64, intervals: &mut Vec<(f64, f64)>) {
        let cz = self.cam.z;
        let (rho_lo, rho_hi) = (self.depth_lo * n, self.depth_hi * n);
        intervals.clear();
        if let Some(iv) = ground_slopes(cz, rho_lo, rho_hi, self.range_hi) {
            intervals.push(iv);
        }
        for b in &self.scene.boxes {
            if let Some(iv) = box_slopes(b, &self.cam, ux / n, uy / n, cz, rho_lo, rho_hi, self.range_hi) {
                intervals.push(iv);
            }
        }
        // Only intervals that reach the image's rows (the ground is often entirely below the frame).
        let scale = self.fl * n;
        let rows_hi = self.h as f64 + 1.0;
        let cy = self.cy;
        intervals.retain(|&(s_lo, s_hi)| cy - scale * s_hi <= rows_hi && cy - scale * s_lo >= -1.0);
    }
}

/// One pixel column's scan: its index `i`, image size `w` x `h`, centre row `cy`, pixels per unit slope
/// `scale`, `1 / n`, its azimuth cell and the cached tangents of the rows and of the 2-degree band edges.
struct Column<'t> {
    i: u32,
    w: u32,
    h: u32,
    cy: f64,
    scale: f64,
    inv_n: f64,
    z_idx: usize,
    az_ambiguous: bool,
    tan_y: &'t [f64],
    tan_band: &'t [f64],
}

impl Column<'_> {
    /// Row `j`'s slope (rise per horizontal metre); band k holds `tan_band[k] <= s < tan_band[k + 1]`.
    fn slope(&self, j: u32) -> f64 {
        -self.tan_y[j as usize] * self.inv_n
    }

    /// Within EDGE_EPS_DEG of a band edge, in slope units (d tan(a) = (1 + tan^2) da).
    fn near_band_edge(&self, s: f64, k: usize) -> bool {
        let eps = EDGE_EPS_DEG.to_radians() * (1.0 + s * s);
        (s - self.tan_band[k]).abs() < eps || (self.tan_band[k + 1] - s).abs() < eps
    }

    fn band_below(&self, s: f64, mut k: usize) -> usize {
        while k > 0 && s < self.tan_band[k] {
            k -= 1;
        }
        k
    }

    /// Offers the first row of each band within the slope interval `[s_lo, s_hi]`.
    fn scan_interval(&self, s_lo: f64, s_hi: f64, scratch: &mut FastRenderScratch) {
        // Slope s of row j is (cy - j) / (fl n): rows from the top edge of the interval down.
        let (top, bottom) = (self.cy - self.scale * s_hi, self.cy - self.scale * s_lo);
        let ja = (-floor_f64(-top)).max(0.0);
        let jb = floor_f64(bottom).min(self.h as f64 - 1.0);
        // Rows at an interval end may be valid or not once parry's f32 ray decides: cast both neighbours.
        for end in [top, bottom] {
            if (end - end.round()).abs() < ROW_EPS && end.round() >= 0.0 {
                let m = end.round() as u32;
                for r in [m.saturating_sub(1), m, m + 1] {
                    if r < self.h {
                        scratch.extras.push(r * self.w + self.i);
                    }
                }
            }
        }
        if ja > jb {
            return;
        }
        let (ja, jb) = (ja as u32, jb as u32);
        let mut j = ja;
        let el0 = self.slope(ja).atan().to_degrees();
        let mut k = (floor_f64(el0 / 2.0 + 45.0) as usize).min(SUB_E - 1);
        loop {
            self.offer_row(j, (ja, jb), k, scratch);
            // The band's lower edge: rows keep band k while their slope >= tan(2k - 90 deg).
            let next = floor_f64(self.cy - self.scale * self.tan_band[k]) + 1.0;
            if next > f64::from(jb) || k == 0 {
                break;
            }
            j = (next as u32).max(j + 1);
            k = self.band_below(self.slope(j), k);
        }
    }

    /// Offers row `j` (the first of band `k` within rows `ja..=jb`) or marks it and its neighbours for casting.
    fn offer_row(&self, j: u32, (ja, jb): (u32, u32), k: usize, scratch: &mut FastRenderScratch) {
        let (i, w) = (self.i, self.w);
        let s_j = self.slope(j);
        // Pixels that may fall on either side of an edge once the planner rounds them are always cast
        // (they never hide another candidate); the next row is then surely inside its band.
        let el_ambiguous = self.near_band_edge(s_j, k);
        if self.az_ambiguous || el_ambiguous {
            scratch.extras.push(j * w + i);
        }
        if el_ambiguous && j < jb {
            if self.az_ambiguous {
                scratch.extras.push((j + 1) * w + i);
            } else {
                let k1 = self.band_below(self.slope(j + 1), k);
                scratch.offer(k1 * SUB_Z + self.z_idx, (j + 1) * w + i);
            }
        } else if !self.az_ambiguous && !el_ambiguous {
            scratch.offer(k * SUB_Z + self.z_idx, j * w + i);
        }
        // The row above (in band k + 1 or higher) may really belong to band k if it is at their edge.
        let eps_prev = |sp: f64| EDGE_EPS_DEG.to_radians() * (1.0 + sp * sp);
        if j > ja && {
            let sp = self.slope(j - 1);
            (sp - self.tan_band[k + 1]).abs() < eps_prev(sp)
        } {
            scratch.extras.push((j - 1) * w + i);
        }
    }
}

/// Ray casts the chosen pixels (each touched cell's first plus every ambiguous one), in pixel order, into `out`.
fn cast_chosen(
    frame: &LevelFrame,
    camera: &Camera,
    pose: &CameraPose,
    scratch: &mut FastRenderScratch,
    out: &mut Vec<Vector3<f32>>,
) {
    let w = frame.w;
    scratch.keys.extend(scratch.touched.iter().map(|&c| scratch.first[c]));
    scratch.keys.extend_from_slice(&scratch.extras);
    scratch.keys.sort_unstable();
    scratch.keys.dedup();
    let rot = pose.rotation();
    for &key in &scratch.keys {
        let (i, j) = (key % w, key / w);
        // The cached tangents are those of `camera` (`prepare`): `ray_body(i, j)` without recomputing them.
        let (tx, ty) = (scratch.tan_x[i as usize], scratch.tan_y[j as usize]);
        let dir = rot * Vector3::new(1.0, -tx, -ty);
        if let Some(d) = frame.scene.cast(&frame.cam, &dir, camera)
            && let Some(p) = pixel_point_enu_tans(camera, pose, &rot, tx, ty, d)
        {
            out.push(p);
        }
    }
}

#[cfg(test)]
#[path = "render_fast_tests.rs"]
mod tests;
