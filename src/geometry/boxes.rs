//! Exact 3-D distances between points or segments and box obstacles, with parry3d.

use parry3d::math::{Isometry, Point, Vector};
use parry3d::query::{self, PointQuery};
use parry3d::shape::{Cuboid, Segment};

use super::footprint::Footprint;

/// A box obstacle standing on the ground: its footprint and its height (metres, up).
///
/// 3-D coordinates are the local ground frame plus height: `x` North, `y` East, `z` up, metres.
#[derive(Debug, Clone)]
pub struct Box3 {
    shape: Cuboid,
    pose: Isometry<f32>,
}

impl Box3 {
    /// The box over `footprint` from the ground up to `height_m`.
    pub fn new(footprint: &Footprint, height_m: f64) -> Self {
        let half = Vector::new(
            footprint.length as f32 / 2.0,
            footprint.width as f32 / 2.0,
            height_m as f32 / 2.0,
        );
        // x-y-z is right-handed with z up, so a counter-clockwise turn from +x to +y is a positive yaw about +z.
        let pose = Isometry::new(
            Vector::new(
                footprint.center.x as f32,
                footprint.center.y as f32,
                height_m as f32 / 2.0,
            ),
            Vector::z() * footprint.yaw_rad as f32,
        );
        Self {
            shape: Cuboid::new(half),
            pose,
        }
    }
}

/// Distance from a point (`x` North, `y` East, `z` up) to the box; 0 inside.
pub fn point_box_distance(b: &Box3, p: [f64; 3]) -> f64 {
    let pt = Point::new(p[0] as f32, p[1] as f32, p[2] as f32);
    f64::from(b.shape.distance_to_point(&b.pose, &pt, true))
}

/// Distance from the segment `a`-`c` to the box; 0 when it touches or enters it.
pub fn segment_box_distance(b: &Box3, a: [f64; 3], c: [f64; 3]) -> f64 {
    let seg = Segment::new(
        Point::new(a[0] as f32, a[1] as f32, a[2] as f32),
        Point::new(c[0] as f32, c[1] as f32, c[2] as f32),
    );
    match query::distance(&Isometry::identity(), &seg, &b.pose, &b.shape) {
        Ok(d) => f64::from(d),
        // parry supports segment-cuboid; fall back to the end points' distance if it ever does not.
        Err(_) => point_box_distance(b, a).min(point_box_distance(b, c)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_and_segment_known_answers() {
        let b = Box3::new(&Footprint::from_aerialist(0.0, 0.0, 4.0, 2.0, 0.0), 10.0);
        assert!((point_box_distance(&b, [5.0, 0.0, 5.0]) - 3.0).abs() < 1e-5);
        assert!((point_box_distance(&b, [0.0, 0.0, 13.0]) - 3.0).abs() < 1e-5);
        assert_eq!(point_box_distance(&b, [0.0, 0.0, 1.0]), 0.0);
        assert!((segment_box_distance(&b, [-9.0, 4.0, 5.0], [9.0, 4.0, 5.0]) - 3.0).abs() < 1e-5);
        assert_eq!(segment_box_distance(&b, [-9.0, 0.0, 5.0], [9.0, 0.0, 5.0]), 0.0);
        // Over the top: 2 m above the roof.
        assert!((segment_box_distance(&b, [-9.0, 0.0, 12.0], [9.0, 0.0, 12.0]) - 2.0).abs() < 1e-5);
    }

    #[test]
    fn rotated_box_matches_footprint_distance() {
        let f = Footprint::from_aerialist(3.0, -2.0, 6.0, 2.0, 30.0);
        let b = Box3::new(&f, 20.0);
        for (x, y) in [(10.0, 0.0), (-4.0, 5.0), (3.0, 6.0)] {
            let d2 = f.distance_to_point(crate::geometry::P2::new(x, y));
            let d3 = point_box_distance(&b, [x, y, 10.0]);
            assert!((d2 - d3).abs() < 1e-4, "{d2} vs {d3}");
        }
    }
}
