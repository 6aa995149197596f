//! Ray-cast depth rendering (parry3d) of the ground plane and a test's boxes, and the point cloud the
//! competition's pipeline makes of it (docs/planner.md §1.5, §10).
//!
//! Everything is in the planner's ENU frame (x East, y North, z Up, metres). The camera sits
//! `mount_forward_m` ahead of the body origin and renders from there; the cloud is then transformed with the
//! launch file's **zero-translation** static TF, as the original pipeline does, so each point lies at
//! `body origin + R * depth * ray_body` (0.1 m nearer the vehicle than the surface it saw, along the view axis).

use nalgebra::{Rotation3, Unit, Vector3};
use parry3d::math::{Isometry, Point, Vector};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::{Cuboid, HalfSpace};

use super::camera::Camera;
use crate::model::Obstacle;

/// Why a pose cannot be rendered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// A coordinate of the pose is NaN or infinite.
    #[error("the pose is not finite")]
    NonFinitePose,
    /// The camera is at or below the ground (height in metres).
    #[error("the camera is under the ground (height {0:.3} m; it must be above 0)")]
    UnderGround(f64),
    /// The camera is inside obstacle `index` (0-based, test order).
    #[error("the camera is inside obstacle {index} (0-based)")]
    InsideBox {
        /// The obstacle's index in the test.
        index: usize,
    },
}

/// Vehicle pose for rendering: body origin (ENU metres), ENU yaw (radians, counter-clockwise from East) and
/// pitch (radians, positive nose-down). The camera is body-fixed, so it pitches with the vehicle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPose {
    /// Body origin, ENU metres.
    pub position_enu: Vector3<f64>,
    /// ENU yaw, radians.
    pub yaw_enu_rad: f64,
    /// Pitch, radians, positive nose-down.
    pub pitch_rad: f64,
}

impl CameraPose {
    /// A level pose.
    pub fn level(position_enu: Vector3<f64>, yaw_enu_rad: f64) -> Self {
        Self {
            position_enu,
            yaw_enu_rad,
            pitch_rad: 0.0,
        }
    }

    /// Body (FLU) to world (ENU) rotation: yaw about +z, then pitch about body +y (left; positive = nose down).
    pub fn rotation(&self) -> Rotation3<f64> {
        Rotation3::from_axis_angle(&Vector3::z_axis(), self.yaw_enu_rad)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), self.pitch_rad)
    }

    /// Where the camera is (ENU metres).
    pub fn camera_position(&self, camera: &Camera) -> Vector3<f64> {
        self.position_enu + self.rotation() * Vector3::new(f64::from(camera.mount_forward_m), 0.0, 0.0)
    }
}

/// One box of the scene in ENU.
#[derive(Debug, Clone)]
pub(crate) struct SceneBox {
    pub(crate) cuboid: Cuboid,
    pub(crate) iso: Isometry<f32>,
    /// Footprint centre, ENU (x East, y North), metres.
    pub(crate) center: [f64; 2],
    /// Unit ENU direction of the box's `l` axis (Aerialist's `r` turns it from North towards East).
    pub(crate) axis_l: [f64; 2],
    pub(crate) half_l: f64,
    pub(crate) half_w: f64,
    /// Base height, metres (0 on the ground).
    pub(crate) base: f64,
    /// Top height, metres.
    pub(crate) top: f64,
}

impl SceneBox {
    fn new(o: &Obstacle) -> Self {
        let f = o.footprint();
        // l axis in NED is (cos r, sin r) (North, East); in ENU (x East, y North) that is (sin r, cos r).
        let axis_l = [f.yaw_rad.sin(), f.yaw_rad.cos()];
        let enu_yaw = axis_l[1].atan2(axis_l[0]);
        let top = o.top_m();
        let base = o.position.z;
        let h = (top - base).max(0.0);
        let cuboid = Cuboid::new(Vector::new(
            (f.length / 2.0) as f32,
            (f.width / 2.0) as f32,
            (h / 2.0) as f32,
        ));
        let iso = Isometry::new(
            Vector::new(f.center.y as f32, f.center.x as f32, (base + h / 2.0) as f32),
            Vector::z() * enu_yaw as f32,
        );
        Self {
            cuboid,
            iso,
            center: [f.center.y, f.center.x],
            axis_l,
            half_l: f.length / 2.0,
            half_w: f.width / 2.0,
            base,
            top,
        }
    }

    /// Footprint-local coordinates (along l, along w) of an ENU ground point.
    pub(crate) fn to_local(&self, x: f64, y: f64) -> (f64, f64) {
        let (dx, dy) = (x - self.center[0], y - self.center[1]);
        let [c, s] = self.axis_l;
        (dx * c + dy * s, -dx * s + dy * c)
    }

    /// 3-D distance from an ENU point to the box (0 inside).
    pub(crate) fn distance(&self, p: &Vector3<f64>) -> f64 {
        let (u, v) = self.to_local(p.x, p.y);
        let du = (u.abs() - self.half_l).max(0.0);
        let dv = (v.abs() - self.half_w).max(0.0);
        let dz = if p.z > self.top {
            p.z - self.top
        } else if p.z < self.base {
            self.base - p.z
        } else {
            0.0
        };
        (du * du + dv * dv + dz * dz).sqrt()
    }

    fn contains(&self, p: &Vector3<f64>) -> bool {
        let (u, v) = self.to_local(p.x, p.y);
        u.abs() < self.half_l && v.abs() < self.half_w && p.z > self.base && p.z < self.top
    }
}

/// The world the camera sees: a ground half-space (z <= 0) and solid boxes, ENU.
#[derive(Debug, Clone)]
pub struct Scene {
    pub(crate) boxes: Vec<SceneBox>,
    ground: HalfSpace,
}

impl Scene {
    /// The ground plus the obstacles' solids (footprint from the foundation, from the base to the top height).
    pub fn new(obstacles: &[Obstacle]) -> Self {
        Self {
            boxes: obstacles.iter().map(SceneBox::new).collect(),
            ground: HalfSpace::new(Unit::new_normalize(Vector::z())),
        }
    }

    /// Number of boxes.
    pub fn box_count(&self) -> usize {
        self.boxes.len()
    }

    /// Rejects poses that cannot be rendered: non-finite, camera or body at/under the ground, or inside a box.
    pub fn check_pose(&self, camera: &Camera, pose: &CameraPose) -> Result<(), RenderError> {
        let ok = pose.position_enu.iter().all(|v| v.is_finite())
            && pose.yaw_enu_rad.is_finite()
            && pose.pitch_rad.is_finite();
        if !ok {
            return Err(RenderError::NonFinitePose);
        }
        let cam = pose.camera_position(camera);
        let low = pose.position_enu.z.min(cam.z);
        if low <= 0.0 {
            return Err(RenderError::UnderGround(low));
        }
        for (index, b) in self.boxes.iter().enumerate() {
            if b.contains(&pose.position_enu) || b.contains(&cam) {
                return Err(RenderError::InsideBox { index });
            }
        }
        Ok(())
    }

    /// Depth (metres along the optical axis) of the first surface at depth >= near clip along the ray
    /// `origin + t * dir` (`dir` scaled to unit depth), if within the far clip. A shape that contains the
    /// near-plane point is seen through, as a rasteriser culls its back faces.
    pub(crate) fn cast(&self, origin: &Vector3<f64>, dir: &Vector3<f64>, camera: &Camera) -> Option<f32> {
        let near = f64::from(camera.near_clip_m);
        let start = origin + dir * near;
        let ray = Ray::new(
            Point::new(start.x as f32, start.y as f32, start.z as f32),
            Vector::new(dir.x as f32, dir.y as f32, dir.z as f32),
        );
        let max_t = camera.far_clip_m - camera.near_clip_m;
        let mut best: Option<f32> = None;
        let mut see = |t: Option<f32>| {
            if let Some(t) = t.filter(|t| *t > 0.0)
                && best.is_none_or(|b| t < b)
            {
                best = Some(t);
            }
        };
        see(self.ground.cast_ray(&Isometry::identity(), &ray, max_t, true));
        for b in &self.boxes {
            see(b.cuboid.cast_ray(&b.iso, &ray, max_t, true));
        }
        best.map(|t| t + camera.near_clip_m)
    }
}

/// A rendered depth image: row-major `height x width`, metres along the optical axis, NaN = no return.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthImage {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `data[j * width + i]` is pixel column `i`, row `j` (row 0 at the top).
    pub data: Vec<f32>,
}

impl DepthImage {
    /// Depth of pixel `(i, j)`.
    pub fn at(&self, i: u32, j: u32) -> f32 {
        self.data[(j * self.width + i) as usize]
    }

    /// The NumPy `.npy` (format 1.0) bytes of the image: little-endian float32, C order, shape `(H, W)`.
    pub fn to_npy(&self) -> Vec<u8> {
        let dict = format!(
            "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}), }}",
            self.height, self.width
        );
        // Magic (6) + version (2) + header length (2) + dict + padding + '\n' is a multiple of 64.
        let unpadded = 10 + dict.len() + 1;
        let pad = (64 - unpadded % 64) % 64;
        let header = format!("{dict}{}\n", " ".repeat(pad));
        let mut out = Vec::with_capacity(10 + header.len() + self.data.len() * 4);
        out.extend_from_slice(b"\x93NUMPY\x01\x00");
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        for v in &self.data {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }
}

/// Renders every pixel (the `render` command and the reference for [`super::render_fast`]).
pub fn render_depth(scene: &Scene, camera: &Camera, pose: &CameraPose) -> Result<DepthImage, RenderError> {
    scene.check_pose(camera, pose)?;
    let rot = pose.rotation();
    let cam = pose.camera_position(camera);
    let (w, h) = (camera.width_px, camera.height_px);
    let mut data = Vec::with_capacity((w * h) as usize);
    for j in 0..h {
        for i in 0..w {
            let dir = rot * camera.ray_body(i, j);
            data.push(scene.cast(&cam, &dir, camera).unwrap_or(f32::NAN));
        }
    }
    Ok(DepthImage {
        width: w,
        height: h,
        data,
    })
}

/// The planner-frame point (ENU, f32) of pixel `(i, j)` at `depth_m`, or `None` outside the plugin's cutoff.
pub fn pixel_point_enu(
    camera: &Camera,
    pose: &CameraPose,
    rot: &Rotation3<f64>,
    i: u32,
    j: u32,
    depth_m: f32,
) -> Option<Vector3<f32>> {
    pixel_point_enu_tans(camera, pose, rot, camera.tan_x(i), camera.tan_y(j), depth_m)
}

/// [`pixel_point_enu`] of the pixel with the given [`Camera::tan_x`] and [`Camera::tan_y`] (cached by callers).
pub fn pixel_point_enu_tans(
    camera: &Camera,
    pose: &CameraPose,
    rot: &Rotation3<f64>,
    tan_x: f64,
    tan_y: f64,
    depth_m: f32,
) -> Option<Vector3<f32>> {
    let optical = camera.optical_from_tans(tan_x, tan_y, depth_m)?;
    let p = pose.position_enu + rot * super::camera::optical_to_body(&optical);
    Some(Vector3::new(p.x as f32, p.y as f32, p.z as f32))
}

/// The cloud of a depth image in pixel order (row-major), as the planner receives it (NaNs removed).
pub fn cloud_from_depth(camera: &Camera, pose: &CameraPose, depth: &DepthImage) -> Vec<Vector3<f32>> {
    let rot = pose.rotation();
    let mut out = Vec::new();
    for j in 0..depth.height {
        for i in 0..depth.width {
            if let Some(p) = pixel_point_enu(camera, pose, &rot, i, j, depth.at(i, j)) {
                out.push(p);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene_one_box() -> Scene {
        // 4 x 2 m footprint (l along North), 20 m tall, centred 10 m North of the origin.
        Scene::new(&[Obstacle::new(4.0, 2.0, 20.0, 10.0, 0.0, 0.0)])
    }

    #[test]
    fn floor_depth_at_known_pose() {
        let scene = Scene::new(&[]);
        let cam = Camera::v2019();
        // 2 m up, level, facing East. The bottom row looks down at atan(23.5 / fl).
        let pose = CameraPose::level(Vector3::new(0.0, 0.0, 2.0), 0.0);
        let img = render_depth(&scene, &cam, &pose).unwrap();
        let j = cam.height_px - 1;
        let expect = 2.0 / cam.tan_y(j); // depth where the ray drops 2 m
        for i in [0, 31, 63] {
            let d = img.at(i, j);
            assert!((f64::from(d) - expect).abs() < 1e-3, "pixel ({i},{j}): {d} vs {expect}");
        }
        // Rows above the horizon see nothing.
        assert!(img.at(10, 0).is_nan());
    }

    #[test]
    fn box_face_depth_at_known_pose() {
        let scene = scene_one_box();
        let cam = Camera::hfs();
        // Facing North (ENU yaw 90 deg) from 3 m South of the origin at 5 m: the face at North = 8 m is 11 m
        // ahead of the body, 10.9 m ahead of the camera, for every pixel that sees it.
        let pose = CameraPose::level(Vector3::new(0.0, -3.0, 5.0), std::f64::consts::FRAC_PI_2);
        let img = render_depth(&scene, &cam, &pose).unwrap();
        let (cx, cy) = (cam.width_px / 2, cam.height_px / 2);
        for (i, j) in [(cx, cy), (cx + 20, cy - 30), (cx - 20, cy + 40)] {
            assert!((img.at(i, j) - 10.9).abs() < 1e-4, "({i},{j}) {}", img.at(i, j));
        }
        // The face is 2 m wide: a pixel 30 degrees to the side misses it.
        assert!(img.at(0, cy).is_nan());
        // Points land on the face shifted 0.1 m back (zero-offset extrinsic): North = 7.9 m.
        let cloud = cloud_from_depth(&cam, &pose, &img);
        assert!(!cloud.is_empty());
        let on_box: Vec<_> = cloud.iter().filter(|p| p.z > 0.5).collect();
        assert!(on_box.len() > 1000);
        assert!(on_box.iter().all(|p| (p.y - 7.9).abs() < 1e-3));
    }

    #[test]
    fn rotated_box_is_placed_like_the_footprint() {
        // r = 90: the 4 m side runs East-West; the box spans East -2..2 at North 10 +- 1.
        let scene = Scene::new(&[Obstacle::new(4.0, 2.0, 20.0, 10.0, 0.0, 90.0)]);
        let cam = Camera::hfs();
        let pose = CameraPose::level(Vector3::new(0.0, 0.0, 5.0), std::f64::consts::FRAC_PI_2);
        let img = render_depth(&scene, &cam, &pose).unwrap();
        let d = img.at(cam.width_px / 2, cam.height_px / 2);
        assert!((d - 8.9).abs() < 1e-4, "{d}");
    }

    #[test]
    fn bad_poses_are_errors() {
        let scene = scene_one_box();
        let cam = Camera::hfs();
        let inside = CameraPose::level(Vector3::new(0.0, 10.0, 5.0), 0.0);
        assert_eq!(
            scene.check_pose(&cam, &inside),
            Err(RenderError::InsideBox { index: 0 })
        );
        let under = CameraPose::level(Vector3::new(0.0, 0.0, -1.0), 0.0);
        assert!(matches!(
            render_depth(&scene, &cam, &under),
            Err(RenderError::UnderGround(_))
        ));
        let nan = CameraPose::level(Vector3::new(f64::NAN, 0.0, 1.0), 0.0);
        assert_eq!(scene.check_pose(&cam, &nan), Err(RenderError::NonFinitePose));
        // Above the box is fine.
        let above = CameraPose::level(Vector3::new(0.0, 10.0, 25.0), 0.0);
        assert!(scene.check_pose(&cam, &above).is_ok());
    }

    #[test]
    fn npy_header_is_valid() {
        let img = DepthImage {
            width: 3,
            height: 2,
            data: vec![1.0, f32::NAN, 2.0, 3.0, 4.0, 5.0],
        };
        let b = img.to_npy();
        assert_eq!(&b[..8], b"\x93NUMPY\x01\x00");
        let hlen = u16::from_le_bytes([b[8], b[9]]) as usize;
        assert_eq!((10 + hlen) % 64, 0);
        let header = std::str::from_utf8(&b[10..10 + hlen]).unwrap();
        assert!(header.contains("'shape': (2, 3)") && header.ends_with('\n'));
        assert_eq!(b.len(), 10 + hlen + 24);
        assert_eq!(f32::from_le_bytes(b[10 + hlen..14 + hlen].try_into().unwrap()), 1.0);
    }

    #[test]
    fn pitch_down_sees_the_floor_nearer() {
        let scene = Scene::new(&[]);
        let cam = Camera::v2019();
        let level = CameraPose::level(Vector3::new(0.0, 0.0, 2.0), 0.0);
        let pitched = CameraPose {
            pitch_rad: 10f64.to_radians(),
            ..level
        };
        let a = render_depth(&scene, &cam, &level).unwrap();
        let b = render_depth(&scene, &cam, &pitched).unwrap();
        assert!(b.at(32, 47) < a.at(32, 47));
        assert!(b.at(32, 24).is_finite() && a.at(32, 24).is_nan());
    }
}
