//! The depth-camera model of the competition's Gazebo vehicle (docs/planner.md §10): intrinsics, clip and cutoff
//! ranges, mount, and the plugin's pixel-to-point rule.
//!
//! Frames: pixel `(i, j)` is column `i` (0 = left) and row `j` (0 = top). The optical frame is x right, y down,
//! z forward; the body frame is FLU (x forward, y left, z up), so body = (optical z, -optical x, -optical y).

use nalgebra::Vector3;

use prgenuav_planner::fov::Fov;

/// A pinhole depth camera looking along body +x, level, mounted `mount_forward_m` ahead of the body origin.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Preset name (`hfs`, `2019`, `d455`) or `custom`.
    pub name: &'static str,
    /// Image width, pixels.
    pub width_px: u32,
    /// Image height, pixels.
    pub height_px: u32,
    /// Full horizontal field of view, degrees.
    pub h_fov_deg: f64,
    /// Near clip plane (depth, metres): closer surfaces are not rendered.
    pub near_clip_m: f32,
    /// Far clip plane (depth, metres): farther surfaces give no return.
    pub far_clip_m: f32,
    /// The plugin keeps a point only if `cutoff_min_m < depth < cutoff_max_m` (metres), else NaN.
    pub cutoff_min_m: f32,
    /// See `cutoff_min_m`.
    pub cutoff_max_m: f32,
    /// Camera position ahead of the body origin along body +x, metres (Gazebo mount 0.1 m).
    pub mount_forward_m: f32,
    /// Downward view tilt of a level camera, radians (0 for the presets): the principal point moves up by
    /// `focal * tan(view_pitch_rad)` pixels, so the centre row looks down by exactly this angle and the others by
    /// about it (the image plane stays vertical: at the HFS camera's top and bottom rows a 5-degree tilt is off by
    /// 0.9 degrees). [`Camera::with_view_pitch`] uses it to stand in for a small body pitch, because the fast
    /// renderer needs vertical image columns.
    pub view_pitch_rad: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Self::hfs()
    }
}

/// Names accepted by [`Camera::preset`].
pub const PRESET_NAMES: [&str; 3] = ["hfs", "2019", "d455"];

impl Camera {
    /// The competition's camera (PX4 v1.12.3 SITL `depth_camera`, 2021-06 model): 59 deg, 640 x 480,
    /// clip 0.5-18 m, points kept at 0.2-20 m depth.
    pub fn hfs() -> Self {
        Self {
            name: "hfs",
            width_px: 640,
            height_px: 480,
            h_fov_deg: 1.02974f64.to_degrees(),
            near_clip_m: 0.5,
            far_clip_m: 18.0,
            cutoff_min_m: 0.2,
            cutoff_max_m: 20.0,
            mount_forward_m: 0.1,
            view_pitch_rad: 0.0,
        }
    }

    /// The 2019 model PX4-Avoidance was tuned with: the HFS camera at 64 x 48 pixels.
    pub fn v2019() -> Self {
        Self {
            name: "2019",
            width_px: 64,
            height_px: 48,
            ..Self::hfs()
        }
    }

    /// The current SITL model (D455-like): 86 deg, 848 x 480, clip 0.001-65.535 m, cutoff 0.2-65.535 m.
    pub fn d455() -> Self {
        Self {
            name: "d455",
            width_px: 848,
            height_px: 480,
            h_fov_deg: 1.500_983_156_7f64.to_degrees(),
            near_clip_m: 0.001,
            far_clip_m: 65.535,
            cutoff_min_m: 0.2,
            cutoff_max_m: 65.535,
            mount_forward_m: 0.1,
            view_pitch_rad: 0.0,
        }
    }

    /// A preset by name (see [`PRESET_NAMES`]).
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "hfs" => Some(Self::hfs()),
            "2019" => Some(Self::v2019()),
            "d455" => Some(Self::d455()),
            _ => None,
        }
    }

    /// Focal length in pixels: `W / (2 tan(HFOV / 2))` (565.6 px for the HFS camera).
    pub fn focal_px(&self) -> f64 {
        self.width_px as f64 / (2.0 * (self.h_fov_deg.to_radians() / 2.0).tan())
    }

    /// Principal point `((W - 1) / 2, (H - 1) / 2)`, pixels (the plugin's convention), the row moved up by
    /// `focal * tan(view_pitch_rad)`.
    pub fn center_px(&self) -> (f64, f64) {
        let shift = if self.view_pitch_rad == 0.0 {
            0.0
        } else {
            self.focal_px() * self.view_pitch_rad.tan()
        };
        (
            (self.width_px as f64 - 1.0) / 2.0,
            (self.height_px as f64 - 1.0) / 2.0 - shift,
        )
    }

    /// This camera tilted down by `pitch_rad` (positive nose-down) through [`Camera::view_pitch_rad`].
    pub fn with_view_pitch(&self, pitch_rad: f64) -> Self {
        Self {
            view_pitch_rad: pitch_rad,
            ..self.clone()
        }
    }

    /// Optical `x / z` of column `i` (`tan(yAngle)` of the plugin).
    pub fn tan_x(&self, i: u32) -> f64 {
        (i as f64 - self.center_px().0) / self.focal_px()
    }

    /// Optical `y / z` of row `j` (`tan(pAngle)`; positive below the axis).
    pub fn tan_y(&self, j: u32) -> f64 {
        (j as f64 - self.center_px().1) / self.focal_px()
    }

    /// Body-frame (FLU) direction of pixel `(i, j)` scaled to unit **depth**: `(1, -tan_x, -tan_y)`.
    /// A point at depth `d` lies at `d` times this vector from the camera.
    pub fn ray_body(&self, i: u32, j: u32) -> Vector3<f64> {
        Vector3::new(1.0, -self.tan_x(i), -self.tan_y(j))
    }

    /// The plugin's pixel-to-point rule (docs/planner.md §10): the optical-frame point `(d tan x, d tan y, d)` of a
    /// pixel with depth `d`, or `None` outside the cutoff `(cutoff_min, cutoff_max)` or when `d` is NaN.
    pub fn pixel_to_optical(&self, i: u32, j: u32, depth_m: f32) -> Option<Vector3<f64>> {
        self.optical_from_tans(self.tan_x(i), self.tan_y(j), depth_m)
    }

    /// [`Camera::pixel_to_optical`] of the pixel whose [`Camera::tan_x`] and [`Camera::tan_y`] are given (callers
    /// that cache them).
    pub fn optical_from_tans(&self, tan_x: f64, tan_y: f64, depth_m: f32) -> Option<Vector3<f64>> {
        if !(depth_m > self.cutoff_min_m && depth_m < self.cutoff_max_m) {
            return None;
        }
        let d = f64::from(depth_m);
        Some(Vector3::new(d * tan_x, d * tan_y, d))
    }

    /// The planner's FOV model of this camera (level, forward; pixel-centre span as the original estimates it).
    pub fn fov(&self) -> Fov {
        Fov::from_pinhole(self.width_px, self.height_px, self.h_fov_deg as f32)
    }

    /// Vertical field of view implied by square pixels, degrees.
    pub fn v_fov_deg(&self) -> f64 {
        2.0 * (self.height_px as f64 / 2.0 / self.focal_px()).atan().to_degrees()
    }
}

/// Optical frame (x right, y down, z forward) to body FLU (x forward, y left, z up): the static TF of the
/// avoidance launch file (yaw -90 deg, roll -90 deg).
pub fn optical_to_body(v: &Vector3<f64>) -> Vector3<f64> {
    Vector3::new(v.z, -v.x, -v.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_the_spec() {
        let c = Camera::hfs();
        assert_eq!((c.width_px, c.height_px), (640, 480));
        assert!((c.h_fov_deg - 59.0).abs() < 0.01);
        assert!((c.focal_px() - 565.6).abs() < 0.1, "{}", c.focal_px());
        assert!((c.v_fov_deg() - 46.0).abs() < 0.1, "{}", c.v_fov_deg());
        assert_eq!((c.near_clip_m, c.far_clip_m), (0.5, 18.0));
        assert_eq!((c.cutoff_min_m, c.cutoff_max_m), (0.2, 20.0));
        let c = Camera::v2019();
        assert_eq!((c.width_px, c.height_px), (64, 48));
        assert!((c.focal_px() - 56.56).abs() < 0.01);
        let c = Camera::d455();
        assert_eq!((c.width_px, c.height_px), (848, 480));
        assert!((c.h_fov_deg - 86.0).abs() < 0.01);
        assert!((c.focal_px() - 454.7).abs() < 0.1, "{}", c.focal_px());
        for n in PRESET_NAMES {
            assert_eq!(Camera::preset(n).map(|c| c.name), Some(n));
        }
        assert!(Camera::preset("kinect").is_none());
        assert_eq!(Camera::default(), Camera::hfs());
    }

    #[test]
    fn pixel_to_point_follows_the_plugin() {
        let c = Camera::v2019();
        // Pixel (0, 0) is top-left: left and up of the axis.
        let p = c.pixel_to_optical(0, 0, 4.0).unwrap();
        assert!((p.x - 4.0 * (-31.5 / c.focal_px())).abs() < 1e-12);
        assert!((p.y - 4.0 * (-23.5 / c.focal_px())).abs() < 1e-12);
        assert_eq!(p.z, 4.0);
        let b = optical_to_body(&p);
        assert!(
            b.x == 4.0 && b.y > 0.0 && b.z > 0.0,
            "top-left is forward, left, up: {b:?}"
        );
        // The ray scaled to unit depth and the optical point agree.
        assert!((c.ray_body(0, 0) * 4.0 - b).norm() < 1e-12);
        // Cutoffs are strict; NaN is no return.
        assert!(c.pixel_to_optical(5, 5, 0.2).is_none());
        assert!(c.pixel_to_optical(5, 5, 20.0).is_none());
        assert!(c.pixel_to_optical(5, 5, f32::NAN).is_none());
        assert!(c.pixel_to_optical(5, 5, 19.9).is_some());
    }

    #[test]
    fn view_pitch_tilts_the_rays_down() {
        let c = Camera::hfs();
        let p = 5f64.to_radians();
        let t = c.with_view_pitch(p);
        assert_eq!(c.with_view_pitch(0.0), c);
        // On the level camera's principal-point row the pitched ray looks down by exactly the pitch (body FLU: z up).
        let (cx, cy) = c.center_px();
        let f = c.focal_px();
        let down = |cam: &Camera, j: u32| -cam.ray_body(0, j).z.atan();
        let j = cy.round() as u32;
        let exact = (j as f64 - cy) / f;
        assert!((down(&t, j) - (exact.atan() + p)).abs() < 1e-3, "{}", down(&t, j));
        // Every row tilts down by about the pitch (within 1 degree at the edges), columns are unchanged.
        for j in [0, 120, 240, 479] {
            let d = down(&t, j) - down(&c, j);
            assert!(
                d > 0.0 && (d - p).abs() < 1f64.to_radians(),
                "row {j}: {}",
                d.to_degrees()
            );
        }
        assert_eq!(t.tan_x(17), c.tan_x(17));
        assert_eq!(t.center_px().0, cx);
    }

    #[test]
    fn extreme_pixels_span_the_planner_fov() {
        let c = Camera::hfs();
        let f = c.fov();
        let left = c.ray_body(0, 240);
        let az = left.y.atan2(left.x).to_degrees();
        assert!(
            (2.0 * az - f64::from(f.h_fov_deg)).abs() < 1e-3,
            "{az} vs {}",
            f.h_fov_deg
        );
    }
}
