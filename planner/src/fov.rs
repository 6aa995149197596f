//! The camera field-of-view model of 3DVFH* (docs/planner.md §3.4, §8.3): inside tests and the edge-of-FOV speed scale.
//!
//! All angles are in degrees in the vehicle body ("fcu") frame, expressed as FCU polar (azimuth counter-clockwise
//! from the body's forward axis, elevation positive **below** the horizon).

use super::polar::{PolarDeg, wrap_180};

/// One camera's field of view in the body frame (degrees).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Fov {
    /// Azimuth of the optical axis, counter-clockwise from body forward, degrees.
    pub yaw_deg: f32,
    /// Elevation of the optical axis, positive below the horizon (nose-down), degrees.
    pub pitch_deg: f32,
    /// Full horizontal field of view, degrees.
    pub h_fov_deg: f32,
    /// Full vertical field of view, degrees.
    pub v_fov_deg: f32,
}

impl Fov {
    /// FOV of a forward, level pinhole camera as the original's data-driven estimate converges to it: the angular
    /// span of the extreme **pixel centres** (AV `updateFOVFromMaxima`), e.g. 58.9 x 45.9 deg for 640 x 480 at
    /// 59 deg horizontal FOV.
    pub fn from_pinhole(width_px: u32, height_px: u32, h_fov_deg: f32) -> Self {
        let fl = width_px as f32 / (2.0 * (h_fov_deg.to_radians() / 2.0).tan());
        let span = |n: u32| 2.0 * ((n as f32 - 1.0) / 2.0 / fl).atan().to_degrees();
        Self {
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            h_fov_deg: span(width_px),
            v_fov_deg: span(height_px),
        }
    }

    /// True if the body-relative FCU polar point lies inside this FOV (yaw and pitch; no handling of a FOV that
    /// straddles +-180, as in the original).
    pub fn contains(&self, p: &PolarDeg) -> bool {
        self.contains_yaw(p)
            && p.e_deg <= self.pitch_deg + self.v_fov_deg / 2.0
            && p.e_deg >= self.pitch_deg - self.v_fov_deg / 2.0
    }

    /// True if the body-relative FCU azimuth lies inside the horizontal FOV.
    pub fn contains_yaw(&self, p: &PolarDeg) -> bool {
        p.z_deg <= wrap_180(self.yaw_deg + self.h_fov_deg / 2.0)
            && p.z_deg >= wrap_180(self.yaw_deg - self.h_fov_deg / 2.0)
    }
}

/// True if the point is inside any of the FOVs (yaw and pitch).
pub fn point_inside_fov(fovs: &[Fov], p: &PolarDeg) -> bool {
    fovs.iter().any(|f| f.contains(p))
}

/// Index of the single FOV whose yaw range holds `p`; `None` if none or more than one does.
fn in_which_fov(fovs: &[Fov], p: &PolarDeg) -> Option<usize> {
    let mut found = None;
    for (i, f) in fovs.iter().enumerate() {
        if f.contains_yaw(p) {
            if found.is_some() {
                return None;
            }
            found = Some(i);
        }
    }
    found
}

/// Speed scale for a body-relative FCU direction (AV `scaleToFOV`): 0 outside every horizontal FOV; a linear taper
/// `1 - 2|daz|/h_fov` when the direction is in a FOV whose edge on that side borders unseen space (always, with one
/// camera); 1 inside overlapping or bordering FOVs.
pub fn scale_to_fov(fovs: &[Fov], p: &PolarDeg) -> f32 {
    if let Some(i) = in_which_fov(fovs, p) {
        let f = &fovs[i];
        let half_res = super::polar::ALPHA_RES as f32 / 2.0;
        let just_outside_z = if wrap_180(p.z_deg - f.yaw_deg) > 0.0 {
            wrap_180(f.yaw_deg + f.h_fov_deg / 2.0 + half_res)
        } else {
            wrap_180(f.yaw_deg - f.h_fov_deg / 2.0 - half_res)
        };
        let outside = PolarDeg {
            z_deg: just_outside_z,
            ..*p
        };
        if !fovs.iter().any(|g| g.contains_yaw(&outside)) {
            let mut diff = (f.yaw_deg - p.z_deg).abs();
            diff = diff.min((360.0 - diff).abs());
            diff = diff.min(f.h_fov_deg / 2.0);
            return 1.0 - 2.0 * diff / f.h_fov_deg;
        }
    }
    if fovs.iter().any(|f| f.contains_yaw(p)) {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(e: f32, z: f32) -> PolarDeg {
        PolarDeg::new(e, z, 1.0)
    }

    #[test]
    fn pinhole_fov_of_competition_camera() {
        let f = Fov::from_pinhole(640, 480, 59.0);
        assert!((f.h_fov_deg - 58.92).abs() < 0.02, "{}", f.h_fov_deg);
        assert!((f.v_fov_deg - 45.91).abs() < 0.02, "{}", f.v_fov_deg);
        let f = Fov::from_pinhole(64, 48, 59.0);
        assert!((f.h_fov_deg - 58.2).abs() < 0.1);
        assert!((f.v_fov_deg - 45.1).abs() < 0.1);
    }

    #[test]
    fn inside_tests_use_both_axes() {
        let f = Fov {
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            h_fov_deg: 60.0,
            v_fov_deg: 40.0,
        };
        assert!(f.contains(&p(0.0, 0.0)));
        assert!(f.contains(&p(20.0, 30.0)));
        assert!(!f.contains(&p(21.0, 0.0)));
        assert!(!f.contains(&p(0.0, -31.0)));
        assert!(f.contains_yaw(&p(80.0, 10.0)));
        let zero = Fov {
            yaw_deg: 1.0,
            pitch_deg: 1.0,
            h_fov_deg: 0.0,
            v_fov_deg: 0.0,
        };
        assert!(!zero.contains(&p(0.0, 0.0)));
    }

    #[test]
    fn speed_scale_tapers_to_the_edge() {
        let fovs = [Fov {
            yaw_deg: 0.0,
            pitch_deg: 0.0,
            h_fov_deg: 60.0,
            v_fov_deg: 40.0,
        }];
        assert_eq!(scale_to_fov(&fovs, &p(0.0, 0.0)), 1.0);
        assert!((scale_to_fov(&fovs, &p(0.0, 15.0)) - 0.5).abs() < 1e-6);
        assert!((scale_to_fov(&fovs, &p(0.0, -15.0)) - 0.5).abs() < 1e-6);
        assert_eq!(scale_to_fov(&fovs, &p(0.0, 30.0)), 0.0);
        assert_eq!(scale_to_fov(&fovs, &p(0.0, 31.0)), 0.0);
        assert_eq!(scale_to_fov(&fovs, &p(0.0, 180.0)), 0.0);
    }

    #[test]
    fn speed_scale_is_one_between_touching_cameras() {
        let fovs = [
            Fov {
                yaw_deg: 0.0,
                pitch_deg: 0.0,
                h_fov_deg: 60.0,
                v_fov_deg: 40.0,
            },
            Fov {
                yaw_deg: 60.0,
                pitch_deg: 0.0,
                h_fov_deg: 60.0,
                v_fov_deg: 40.0,
            },
        ];
        // 20 deg is in the first camera only, but the space just beyond its left edge is seen by the second.
        assert_eq!(scale_to_fov(&fovs, &p(0.0, 20.0)), 1.0);
        assert!(scale_to_fov(&fovs, &p(0.0, -20.0)) < 0.5);
    }
}
