//! A horizontal range scan of boxes, as an OBSTACLE_DISTANCE message: the sensor a Collision Prevention test
//! streams to the vehicle. The vehicle itself never reads it; Collision Prevention sees only what arrives.
//!
//! The message is body-frame (`MAV_FRAME_BODY_FRD`), 5-degree sectors on PX4's bin grid (sector 0 straight
//! ahead), so each sector fills exactly one bin. Sectors outside the field of view are unknown (`u16::MAX`);
//! a ray that hits nothing within range reads `max_distance + 1`.

use mavlink::dialects::common::{MavDistanceSensor, MavFrame, OBSTACLE_DISTANCE_DATA};

use crate::dynamics::Ned;
use crate::obstacle_map::{BIN_COUNT, BIN_DEG, UNKNOWN};
use crate::obstacles::SolidBox;

/// A range sensor's shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeSensor {
    /// Horizontal field of view, degrees, centred ahead (360: all around).
    pub fov_deg: f64,
    /// Shortest distance measured, m.
    pub min_m: f64,
    /// Longest distance measured, m.
    pub max_m: f64,
}

/// Distance (m) along the horizontal unit ray `dir` (x North, y East) from `from` to the box, at `from`'s
/// height; None if the ray misses or the height is outside the box.
pub fn ray_to_box(b: &SolidBox, from: &Ned, dir: (f64, f64)) -> Option<f64> {
    let up = -from.z;
    if up < b.bottom_m || up > b.top_m {
        return None;
    }
    let (s, c) = b.r_deg.to_radians().sin_cos();
    // Into the box's own axes.
    let (dx, dy) = (from.x - b.x, from.y - b.y);
    let o = [dx * c + dy * s, -dx * s + dy * c];
    let d = [dir.0 * c + dir.1 * s, -dir.0 * s + dir.1 * c];
    let half = [b.l / 2.0, b.w / 2.0];
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..2 {
        if d[k].abs() < 1e-12 {
            if o[k].abs() > half[k] {
                return None;
            }
            continue;
        }
        let (a, e) = ((-half[k] - o[k]) / d[k], (half[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(e));
        t1 = t1.min(a.max(e));
    }
    (t0 <= t1).then_some(t0)
}

impl RangeSensor {
    /// The scan from `pos` (local NED) at heading `yaw_rad` (0 North, clockwise).
    pub fn scan(&self, boxes: &[SolidBox], pos: &Ned, yaw_rad: f64, time_usec: u64) -> OBSTACLE_DISTANCE_DATA {
        let max_cm = (self.max_m * 100.0).clamp(1.0, 65533.0) as u16;
        let mut distances = [UNKNOWN; BIN_COUNT];
        for (i, out) in distances.iter_mut().enumerate() {
            let rel = (i as f64 * f64::from(BIN_DEG) + 180.0).rem_euclid(360.0) - 180.0;
            if rel.abs() > self.fov_deg / 2.0 {
                continue;
            }
            let a = yaw_rad + rel.to_radians();
            let hit = boxes
                .iter()
                .filter_map(|b| ray_to_box(b, pos, (a.cos(), a.sin())))
                .fold(f64::INFINITY, f64::min);
            *out = if hit <= self.max_m {
                (hit.max(self.min_m) * 100.0).round() as u16
            } else {
                max_cm + 1
            };
        }
        OBSTACLE_DISTANCE_DATA {
            time_usec,
            distances,
            min_distance: (self.min_m * 100.0).clamp(0.0, 65533.0) as u16,
            max_distance: max_cm,
            sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
            increment: BIN_DEG as u8,
            increment_f: 0.0,
            angle_offset: 0.0,
            frame: MavFrame::MAV_FRAME_BODY_FRD,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wall() -> SolidBox {
        // 2 m thick, 40 m wide, across North at x 9..11, 0..20 m high.
        SolidBox {
            x: 10.0,
            y: 0.0,
            l: 2.0,
            w: 40.0,
            r_deg: 0.0,
            bottom_m: 0.0,
            top_m: 20.0,
        }
    }

    #[test]
    fn rays_hit_the_near_face_and_miss_above_or_behind() {
        let at = Ned::new(0.0, 0.0, -5.0);
        assert!((ray_to_box(&wall(), &at, (1.0, 0.0)).unwrap() - 9.0).abs() < 1e-9);
        assert_eq!(ray_to_box(&wall(), &at, (-1.0, 0.0)), None);
        assert_eq!(ray_to_box(&wall(), &Ned::new(0.0, 0.0, -25.0), (1.0, 0.0)), None);
        // Turned 90 degrees, the wall runs North-South: 40 m long along x, 2 m across y at y 9..11.
        let turned = SolidBox {
            y: 10.0,
            x: 0.0,
            r_deg: 90.0,
            ..wall()
        };
        assert!((ray_to_box(&turned, &at, (0.0, 1.0)).unwrap() - 9.0).abs() < 1e-9);
    }

    #[test]
    fn the_scan_is_body_frame_within_its_field_of_view() {
        let s = RangeSensor {
            fov_deg: 90.0,
            min_m: 0.2,
            max_m: 20.0,
        };
        let at = Ned::new(0.0, 0.0, -5.0);
        let m = s.scan(&[wall()], &at, 0.0, 7);
        assert_eq!(m.distances[0], 900);
        assert_eq!(m.distances[9], 1273); // 45 degrees: 9 / cos 45
        assert_eq!(m.distances[10], UNKNOWN);
        assert_eq!(m.distances[71], 903); // -5 degrees: 9 / cos 5
        // Facing East, the wall is at -90 degrees: outside the view.
        let m = s.scan(&[wall()], &at, 90f64.to_radians(), 7);
        assert_eq!(m.distances[0], 2001);
        assert_eq!(m.distances[63], 1273);
        assert_eq!(m.distances[54], UNKNOWN);
    }
}
