//! Distances and crossings between points and segments on the ground plane.

use super::{P2, V2};

/// Distance from `p` to the closed segment `a`-`b` (a degenerate segment is a point).
pub fn point_segment_distance(p: P2, a: P2, b: P2) -> f64 {
    (p - closest_on_segment(p, a, b)).norm()
}

/// The point of segment `a`-`b` closest to `p`.
pub fn closest_on_segment(p: P2, a: P2, b: P2) -> P2 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 == 0.0 {
        return a;
    }
    let t = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    a + ab * t
}

fn cross(u: V2, v: V2) -> f64 {
    u.x * v.y - u.y * v.x
}

/// Whether the closed segments `a`-`b` and `c`-`d` share at least one point (touching counts).
pub fn segments_intersect(a: P2, b: P2, c: P2, d: P2) -> bool {
    let d1 = cross(d - c, a - c);
    let d2 = cross(d - c, b - c);
    let d3 = cross(b - a, c - a);
    let d4 = cross(b - a, d - a);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    // Collinear or end-point cases: an end point lies on the other segment.
    (d1 == 0.0 && on_segment(a, c, d))
        || (d2 == 0.0 && on_segment(b, c, d))
        || (d3 == 0.0 && on_segment(c, a, b))
        || (d4 == 0.0 && on_segment(d, a, b))
}

fn on_segment(p: P2, a: P2, b: P2) -> bool {
    p.x >= a.x.min(b.x) && p.x <= a.x.max(b.x) && p.y >= a.y.min(b.y) && p.y <= a.y.max(b.y)
}

/// Distance between the closed segments `a`-`b` and `c`-`d`; 0 when they cross or touch.
pub fn segment_segment_distance(a: P2, b: P2, c: P2, d: P2) -> f64 {
    if segments_intersect(a, b, c, d) {
        return 0.0;
    }
    point_segment_distance(a, c, d)
        .min(point_segment_distance(b, c, d))
        .min(point_segment_distance(c, a, b))
        .min(point_segment_distance(d, a, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> P2 {
        P2::new(x, y)
    }

    #[test]
    fn point_to_segment_interior_and_ends() {
        assert_eq!(point_segment_distance(p(0.5, 2.0), p(0.0, 0.0), p(1.0, 0.0)), 2.0);
        assert_eq!(point_segment_distance(p(4.0, 4.0), p(0.0, 0.0), p(1.0, 0.0)), 5.0);
        assert_eq!(point_segment_distance(p(3.0, 4.0), p(0.0, 0.0), p(0.0, 0.0)), 5.0);
    }

    #[test]
    fn crossing_touching_and_parallel_segments() {
        assert!(segments_intersect(p(0.0, 0.0), p(2.0, 2.0), p(0.0, 2.0), p(2.0, 0.0)));
        assert!(segments_intersect(p(0.0, 0.0), p(1.0, 0.0), p(1.0, 0.0), p(1.0, 5.0)));
        assert!(segments_intersect(p(0.0, 0.0), p(2.0, 0.0), p(1.0, 0.0), p(3.0, 0.0)));
        assert!(!segments_intersect(p(0.0, 0.0), p(1.0, 0.0), p(2.0, 0.0), p(3.0, 0.0)));
        assert_eq!(
            segment_segment_distance(p(0.0, 0.0), p(4.0, 0.0), p(1.0, 3.0), p(3.0, 3.0)),
            3.0
        );
        assert_eq!(
            segment_segment_distance(p(0.0, 0.0), p(2.0, 2.0), p(0.0, 2.0), p(2.0, 0.0)),
            0.0
        );
    }
}
