//! Point-cloud processing and memory (`processPointcloud`, docs/planner.md §3): 2-degree subsampling of each new frame
//! plus remembered points that are outside the camera FOV, younger than the age limit and within range.
//!
//! Points are ENU (x East, y North, z Up, metres) in the world frame; ages are seconds. Storage is
//! structure-of-arrays because every tree node rebuilds a histogram from the whole memory.

use nalgebra::Vector3;

use super::fov::{Fov, point_inside_fov};
use super::histogram::cell_and_range;
use super::params::PlannerParams;
use super::polar::{
    FAST_ATAN2_MAX_ERR_DEG, PolarDeg, cartesian_to_polar_fcu, fast_atan2_deg, floor_f32, wrap_180, wrap_polar,
};

/// Subsampling cell size: ALPHA_RES / SCALE_FACTOR = 6 / 3 = 2 degrees.
const SUBSAMPLE_RES_DEG: i32 = 2;
const SUB_E: usize = 90;
const SUB_Z: usize = 180;

/// Vehicle state needed to process one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CloudPose {
    /// Vehicle position, ENU metres.
    pub position_enu: Vector3<f32>,
    /// Vehicle ENU yaw in degrees (counter-clockwise from East).
    pub yaw_enu_deg: f32,
    /// Vehicle pitch in degrees, positive nose-down (the camera looks down).
    pub pitch_deg: f32,
}

/// The processed cloud (`final_cloud`): at most one new point per 2-degree cell plus remembered points.
#[derive(Debug, Clone, Default)]
pub struct PointMemory {
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    ages_s: Vec<f32>,
    // Scratch: 2-degree cell counters, valid only where `stamp == generation` (avoids clearing 16k cells).
    counts: Vec<u32>,
    stamps: Vec<u32>,
    generation: u32,
    spare: [Vec<f32>; 4],
}

impl PointMemory {
    /// An empty memory.
    pub fn new() -> Self {
        Self {
            counts: vec![0; SUB_E * SUB_Z],
            stamps: vec![0; SUB_E * SUB_Z],
            ..Default::default()
        }
    }

    /// A memory holding exactly `points` (ENU metres) with age 0, without subsampling (as `setPointcloud`).
    pub fn from_points(points: &[Vector3<f32>]) -> Self {
        let mut m = Self::new();
        for p in points {
            m.push(p.x, p.y, p.z, 0.0);
        }
        m
    }

    /// Number of points held.
    pub fn len(&self) -> usize {
        self.xs.len()
    }

    /// True if no point is held.
    pub fn is_empty(&self) -> bool {
        self.xs.is_empty()
    }

    /// X (East), Y (North) and Z (Up) coordinates in metres, as parallel slices.
    pub fn soa(&self) -> (&[f32], &[f32], &[f32]) {
        (&self.xs, &self.ys, &self.zs)
    }

    /// Points (ENU metres) with their age in seconds (0 = from the latest frame).
    pub fn points(&self) -> impl Iterator<Item = (Vector3<f32>, f32)> + '_ {
        (0..self.xs.len()).map(|i| (Vector3::new(self.xs[i], self.ys[i], self.zs[i]), self.ages_s[i]))
    }

    /// Forgets everything.
    pub fn clear(&mut self) {
        self.xs.clear();
        self.ys.clear();
        self.zs.clear();
        self.ages_s.clear();
    }

    /// Processes one frame (all cameras' points concatenated in camera order, ENU world frame) taken at `pose`,
    /// `elapsed_s` after the previous call. Non-finite points are ignored.
    ///
    /// New points: kept if `min < range < max` (strict), and only the `min_num_points_per_cell`-th point of each
    /// 2-degree cell (seen from the vehicle) is kept, with age 0. Old points: kept (age += elapsed) if within
    /// `max` range (no minimum), in a 2-degree cell without enough new points, younger than `max_point_age_s`,
    /// and outside every camera FOV; each kept old point fills its cell, so at most one survives per cell.
    pub fn process(
        &mut self,
        new_points_enu: &[Vector3<f32>],
        pose: &CloudPose,
        params: &PlannerParams,
        elapsed_s: f32,
    ) {
        if self.counts.len() != SUB_E * SUB_Z {
            *self = Self {
                xs: std::mem::take(&mut self.xs),
                ..Self::new()
            };
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamps.fill(0);
            self.generation = 1;
        }
        let old = [
            std::mem::replace(&mut self.xs, std::mem::take(&mut self.spare[0])),
            std::mem::replace(&mut self.ys, std::mem::take(&mut self.spare[1])),
            std::mem::replace(&mut self.zs, std::mem::take(&mut self.spare[2])),
            std::mem::replace(&mut self.ages_s, std::mem::take(&mut self.spare[3])),
        ];
        self.clear();

        let pos = pose.position_enu;
        let min2 = params.min_sensor_range_m * params.min_sensor_range_m;
        let max2 = params.max_sensor_range_m * params.max_sensor_range_m;
        let threshold = params.min_num_points_per_cell;
        for p in new_points_enu {
            if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
                continue;
            }
            let (dx, dy, dz) = (p.x - pos.x, p.y - pos.y, p.z - pos.z);
            let d2 = dx * dx + dy * dy + dz * dz;
            if !(min2 < d2 && d2 < max2) {
                continue;
            }
            let cell = self.cell(dx, dy, dz);
            let count = self.bump(cell);
            if count == threshold {
                self.push(p.x, p.y, p.z, 0.0);
            }
        }

        let [oxs, oys, ozs, oages] = &old;
        for i in 0..oxs.len() {
            let (dx, dy, dz) = (oxs[i] - pos.x, oys[i] - pos.y, ozs[i] - pos.z);
            if dx * dx + dy * dy + dz * dz >= max2 {
                continue;
            }
            let cell = self.cell(dx, dy, dz);
            if self.count(cell) < threshold
                && oages[i] < params.max_point_age_s
                && !inside_fov_body(&params.fovs, dx, dy, dz, pose)
            {
                self.push(oxs[i], oys[i], ozs[i], oages[i] + elapsed_s);
                self.stamps[cell] = self.generation;
                self.counts[cell] = threshold;
            }
        }
        self.spare = old;
    }

    fn cell(&self, dx: f32, dy: f32, dz: f32) -> usize {
        let (c, _) = cell_and_range(dx, dy, dz, SUBSAMPLE_RES_DEG);
        c.e * SUB_Z + c.z
    }

    fn count(&self, cell: usize) -> u32 {
        if self.stamps[cell] == self.generation {
            self.counts[cell]
        } else {
            0
        }
    }

    fn bump(&mut self, cell: usize) -> u32 {
        let n = self.count(cell).saturating_add(1);
        self.stamps[cell] = self.generation;
        self.counts[cell] = n;
        n
    }

    fn push(&mut self, x: f32, y: f32, z: f32, age_s: f32) {
        self.xs.push(x);
        self.ys.push(y);
        self.zs.push(z);
        self.ages_s.push(age_s);
    }
}

/// Decisions closer than this (degrees) to a wrap or FOV bound are recomputed exactly.
const FOV_MARGIN_DEG: f32 = 5.0 * FAST_ATAN2_MAX_ERR_DEG;

/// Is the offset `d` (ENU, from the vehicle) inside a camera FOV once turned into body-relative FCU polar
/// (FCU azimuth - yaw, FCU elevation - pitch, wrapped)? Exactly the original's test: a fast arctangent decides
/// unless some intermediate angle is within a margin of a wrap or a bound, then the exact path decides.
fn inside_fov_body(fovs: &[Fov], dx: f32, dy: f32, dz: f32, pose: &CloudPose) -> bool {
    fast_inside_fov_body(fovs, dx, dy, dz, pose).unwrap_or_else(|| {
        let mut p = cartesian_to_polar_fcu(&Vector3::new(dx, dy, dz), &Vector3::zeros());
        p.e_deg -= pose.pitch_deg;
        p.z_deg -= pose.yaw_enu_deg;
        point_inside_fov(fovs, &wrap_polar(p))
    })
}

fn near(a: f32, b: f32) -> bool {
    (a - b).abs() < FOV_MARGIN_DEG
}

/// Near a discontinuity of `wrap_180` (an odd multiple of 180 degrees)?
fn near_wrap(a: f32) -> bool {
    let u = (a - 180.0) / 360.0;
    let f = u - floor_f32(u);
    f.min(1.0 - f) * 360.0 < FOV_MARGIN_DEG
}

fn fast_inside_fov_body(fovs: &[Fov], dx: f32, dy: f32, dz: f32, pose: &CloudPose) -> Option<bool> {
    let den = (dx * dx + dy * dy).sqrt();
    let h_e = fast_atan2_deg(dz, den);
    let h_z = fast_atan2_deg(dx, dy);
    // FCU polar: elevation -h_e (no fold possible), azimuth 90 - h_z.
    let z1 = -h_z + 90.0;
    if near_wrap(z1) || near(h_e.abs(), 90.0) {
        return None;
    }
    let e2 = -h_e - pose.pitch_deg;
    let z2 = wrap_180(z1) - pose.yaw_enu_deg;
    if near_wrap(e2) || near_wrap(z2) || near(wrap_180(e2).abs(), 90.0) {
        return None;
    }
    // A fold over a pole shifts the azimuth by 180 towards zero, which is discontinuous at 0.
    if wrap_180(e2).abs() > 90.0 && near(wrap_180(z2), 0.0) {
        return None;
    }
    let p = wrap_polar(PolarDeg::new(e2, z2, 1.0));
    if near_wrap(p.z_deg) {
        return None;
    }
    for f in fovs {
        let bounds_z = [
            wrap_180(f.yaw_deg + f.h_fov_deg / 2.0),
            wrap_180(f.yaw_deg - f.h_fov_deg / 2.0),
        ];
        let bounds_e = [f.pitch_deg + f.v_fov_deg / 2.0, f.pitch_deg - f.v_fov_deg / 2.0];
        if bounds_z.iter().any(|&b| near(p.z_deg, b)) || bounds_e.iter().any(|&b| near(p.e_deg, b)) {
            return None;
        }
    }
    Some(point_inside_fov(fovs, &p))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pose(pos: Vector3<f32>) -> CloudPose {
        CloudPose {
            position_enu: pos,
            yaw_enu_deg: 0.0,
            pitch_deg: 0.0,
        }
    }

    #[test]
    fn known_answer_av_process_pointcloud() {
        // docs/planner.md §3 / AV test processPointcloud: 6 + 3 new points (one too far, one too close), one memory
        // point 1.4 m East (straight ahead for yaw 0) aged 5 s.
        let position = Vector3::new(1.5, 1.0, 4.5);
        let offs = [
            (1.1, 0.8, 0.1),
            (2.2, 1.0, 1.0),
            (1.0, -3.0, 1.0),
            (0.7, 0.3, -0.5),
            (-1.0, 1.0, 1.0),
            (-1.0, -1.1, 3.5),
            (1.0, 5.0, 1.0),
            (100.0, 5.0, 1.0),
            (0.1, 0.05, 0.05),
        ];
        let new: Vec<_> = offs.iter().map(|&(x, y, z)| position + Vector3::new(x, y, z)).collect();
        let fov_zero = vec![Fov {
            yaw_deg: 1.0,
            pitch_deg: 1.0,
            h_fov_deg: 0.0,
            v_fov_deg: 0.0,
        }];
        let fov_regular = vec![Fov {
            yaw_deg: 0.0,
            pitch_deg: 1.0,
            h_fov_deg: 85.0,
            v_fov_deg: 65.0,
        }];
        let run = |fovs: Vec<Fov>, max_age: f32| {
            let params = PlannerParams {
                min_sensor_range_m: 0.2,
                max_sensor_range_m: 12.0,
                max_point_age_s: max_age,
                fovs,
                ..Default::default()
            };
            let mut m = PointMemory::new();
            let mem = position + Vector3::new(1.4, 0.0, 0.0);
            m.push(mem.x, mem.y, mem.z, 5.0);
            m.process(&new, &pose(position), &params, 0.5);
            m
        };
        assert_eq!(run(fov_zero.clone(), 0.0).len(), 7);
        let kept = run(fov_zero, 10.0);
        assert_eq!(kept.len(), 8);
        assert_eq!(kept.points().last().map(|(_, a)| a), Some(5.5));
        assert_eq!(run(fov_regular, 10.0).len(), 7);
    }

    #[test]
    fn only_the_first_point_per_two_degree_cell_is_kept() {
        let params = PlannerParams::default();
        let o = Vector3::zeros();
        // Same direction, different ranges -> same cell; the first in input order wins.
        let pts = [
            Vector3::new(5.0, 0.02, 0.0),
            Vector3::new(9.0, 0.03, 0.0),
            Vector3::new(0.0, 7.0, 0.0),
        ];
        let mut m = PointMemory::new();
        m.process(&pts, &pose(o), &params, 0.1);
        let kept: Vec<_> = m.points().map(|(p, _)| p).collect();
        assert_eq!(kept, vec![pts[0], pts[2]]);
        // With a threshold of 2 the second point of the cell is kept and single points are dropped.
        let params2 = PlannerParams {
            min_num_points_per_cell: 2,
            ..Default::default()
        };
        m.clear();
        m.process(&pts, &pose(o), &params2, 0.1);
        assert_eq!(m.points().map(|(p, _)| p).collect::<Vec<_>>(), vec![pts[1]]);
    }

    #[test]
    fn memory_rules_fov_age_range_and_new_data() {
        let params = PlannerParams::default(); // ~59 x 46 deg camera, 15 m, 20 s
        let mut m = PointMemory::new();
        let ahead = Vector3::new(6.0, 0.0, 0.0); // East, in view at yaw 0
        m.process(&[ahead], &pose(Vector3::zeros()), &params, 0.0);
        assert_eq!(m.len(), 1);
        // Still in the FOV and no new data: forgotten (the current frame alone describes the FOV).
        m.process(&[], &pose(Vector3::zeros()), &params, 0.1);
        assert_eq!(m.len(), 0);
        // Seen, then the vehicle turns North (yaw 90): the point is now outside the FOV and remembered.
        m.process(&[ahead], &pose(Vector3::zeros()), &params, 0.0);
        let turned = CloudPose {
            yaw_enu_deg: 90.0,
            ..pose(Vector3::zeros())
        };
        for k in 1..=3 {
            m.process(&[], &turned, &params, 0.5);
            assert_eq!(m.points().next().map(|(_, a)| a), Some(0.5 * k as f32));
        }
        // Too old: forgotten once age >= max_point_age_s.
        let old = PlannerParams {
            max_point_age_s: 1.5,
            ..Default::default()
        };
        m.process(&[], &turned, &old, 0.5);
        assert_eq!(m.len(), 0);
        // Beyond max range from the new position: forgotten; closer than min range is kept for old points.
        m.process(&[ahead], &pose(Vector3::zeros()), &params, 0.0);
        m.process(
            &[],
            &CloudPose {
                position_enu: Vector3::new(6.1, 0.0, 0.0),
                ..turned
            },
            &params,
            0.1,
        );
        assert_eq!(m.len(), 1, "old points have no minimum range");
        m.process(
            &[],
            &CloudPose {
                position_enu: Vector3::new(-10.0, 0.0, 0.0),
                ..turned
            },
            &params,
            0.1,
        );
        assert_eq!(m.len(), 0);
    }

    #[test]
    fn new_point_in_a_cell_replaces_the_old_one_and_nans_are_ignored() {
        let params = PlannerParams::default();
        let mut m = PointMemory::new();
        let behind = Vector3::new(-5.0, 0.0, 0.0); // West, outside the FOV at yaw 0
        m.process(&[behind], &pose(Vector3::zeros()), &params, 0.0);
        let newer = Vector3::new(-7.0, 0.01, 0.0);
        m.process(
            &[newer, Vector3::new(f32::NAN, 0.0, 0.0)],
            &pose(Vector3::zeros()),
            &params,
            0.1,
        );
        assert_eq!(m.points().collect::<Vec<_>>(), vec![(newer, 0.0)]);
    }

    #[test]
    fn fast_fov_test_equals_exact_on_a_dense_sweep() {
        let mut s: u64 = 12345;
        let mut next = || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((s >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        let fov_sets = [
            PlannerParams::default().fovs,
            vec![Fov {
                yaw_deg: 170.0,
                pitch_deg: -80.0,
                h_fov_deg: 40.0,
                v_fov_deg: 30.0,
            }],
            vec![Fov {
                yaw_deg: 0.0,
                pitch_deg: 1.0,
                h_fov_deg: 85.0,
                v_fov_deg: 65.0,
            }],
        ];
        for i in 0..100_000 {
            let (x, y, z) = (next() * 15.0, next() * 15.0, next() * 15.0);
            let pose = CloudPose {
                position_enu: Vector3::zeros(),
                yaw_enu_deg: next() * 200.0,
                pitch_deg: next() * 100.0,
            };
            let fovs = &fov_sets[i % 3];
            let mut p = cartesian_to_polar_fcu(&Vector3::new(x, y, z), &Vector3::zeros());
            p.e_deg -= pose.pitch_deg;
            p.z_deg -= pose.yaw_enu_deg;
            let exact = point_inside_fov(fovs, &wrap_polar(p));
            assert_eq!(inside_fov_body(fovs, x, y, z, &pose), exact, "{x} {y} {z} {pose:?}");
        }
    }

    proptest! {
        #[test]
        fn fast_fov_test_equals_exact(
            x in -20.0f32..20.0, y in -20.0f32..20.0, z in -20.0f32..20.0,
            yaw in -180.0f32..180.0, pitch in -30.0f32..30.0
        ) {
            let fovs = PlannerParams::default().fovs;
            let pose = CloudPose { position_enu: Vector3::zeros(), yaw_enu_deg: yaw, pitch_deg: pitch };
            let mut p = cartesian_to_polar_fcu(&Vector3::new(x, y, z), &Vector3::zeros());
            p.e_deg -= pitch;
            p.z_deg -= yaw;
            let exact = point_inside_fov(&fovs, &wrap_polar(p));
            prop_assert_eq!(inside_fov_body(&fovs, x, y, z, &pose), exact);
        }
    }
}
