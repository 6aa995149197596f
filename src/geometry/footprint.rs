//! The footprint of a box obstacle: a rectangle rotated about its centre on the ground plane.

use super::segment::{closest_on_segment, segments_intersect};
use super::{P2, V2};

/// A rotated rectangle in the local ground frame (`x` North, `y` East, metres).
///
/// The unrotated rectangle is `[-length/2, length/2] x [-width/2, width/2]`; it is rotated by `yaw_rad`
/// counter-clockwise in the x-y plane (from +x towards +y, as Aerialist's `r`), then moved to `center`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Footprint {
    /// Centre of the rectangle.
    pub center: P2,
    /// Side along the rotated x axis, metres (> 0).
    pub length: f64,
    /// Side along the rotated y axis, metres (> 0).
    pub width: f64,
    /// Rotation from +x towards +y, radians.
    pub yaw_rad: f64,
}

impl Footprint {
    /// A footprint from Aerialist's obstacle fields: centre, `l`, `w` and `r` in degrees.
    pub fn from_aerialist(x: f64, y: f64, l: f64, w: f64, r_deg: f64) -> Self {
        Self {
            center: P2::new(x, y),
            length: l,
            width: w,
            yaw_rad: r_deg.to_radians(),
        }
    }

    /// Unit vectors of the rectangle's length and width axes.
    pub fn axes(&self) -> (V2, V2) {
        let (s, c) = self.yaw_rad.sin_cos();
        (V2::new(c, s), V2::new(-s, c))
    }

    /// The four corners, counter-clockwise, starting at (-l/2, -w/2) in the rectangle's own axes.
    pub fn corners(&self) -> [P2; 4] {
        let (u, v) = self.axes();
        let (hl, hw) = (self.length / 2.0, self.width / 2.0);
        [
            self.center - u * hl - v * hw,
            self.center + u * hl - v * hw,
            self.center + u * hl + v * hw,
            self.center - u * hl + v * hw,
        ]
    }

    /// The four edges as corner pairs, in the order of [`Footprint::corners`].
    pub fn edges(&self) -> [(P2, P2); 4] {
        let c = self.corners();
        [(c[0], c[1]), (c[1], c[2]), (c[2], c[3]), (c[3], c[0])]
    }

    /// `p` in the rectangle's own axes (origin at the centre).
    pub fn to_local(&self, p: P2) -> V2 {
        let (u, v) = self.axes();
        let d = p - self.center;
        V2::new(d.dot(&u), d.dot(&v))
    }

    /// Whether `p` lies inside or on the border.
    pub fn contains(&self, p: P2) -> bool {
        let q = self.to_local(p);
        q.x.abs() <= self.length / 2.0 && q.y.abs() <= self.width / 2.0
    }

    /// Distance from `p` to the rectangle; 0 inside.
    pub fn distance_to_point(&self, p: P2) -> f64 {
        let q = self.to_local(p);
        let dx = (q.x.abs() - self.length / 2.0).max(0.0);
        let dy = (q.y.abs() - self.width / 2.0).max(0.0);
        dx.hypot(dy)
    }

    /// Distance from the closed segment `a`-`b` to the rectangle; 0 when it touches or enters it.
    pub fn distance_to_segment(&self, a: P2, b: P2) -> f64 {
        if self.contains(a) || self.contains(b) {
            return 0.0;
        }
        // Closest pair between two non-crossing segments has an end point on one of them: the segment's ends
        // against the rectangle, and each corner against the segment.
        let mut best = self.distance_to_point(a).min(self.distance_to_point(b));
        for (c, d) in self.edges() {
            if segments_intersect(a, b, c, d) {
                return 0.0;
            }
            best = best.min((c - closest_on_segment(c, a, b)).norm());
        }
        best
    }

    /// Distance from a polyline to the rectangle (minimum over its segments); a single point counts.
    pub fn distance_to_polyline(&self, points: &[P2]) -> Option<f64> {
        match points {
            [] => None,
            [p] => Some(self.distance_to_point(*p)),
            _ => Some(
                points
                    .windows(2)
                    .map(|w| self.distance_to_segment(w[0], w[1]))
                    .fold(f64::INFINITY, f64::min),
            ),
        }
    }

    /// The parameter interval `[t0, t1]` of segment `a + t (b - a)`, `t` in [0, 1], inside the rectangle.
    pub fn clip_segment(&self, a: P2, b: P2) -> Option<(f64, f64)> {
        let (qa, qb) = (self.to_local(a), self.to_local(b));
        let d = qb - qa;
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (q, dq, half) in [(qa.x, d.x, self.length / 2.0), (qa.y, d.y, self.width / 2.0)] {
            if dq == 0.0 {
                if q.abs() > half {
                    return None;
                }
                continue;
            }
            let (mut lo, mut hi) = ((-half - q) / dq, (half - q) / dq);
            if lo > hi {
                std::mem::swap(&mut lo, &mut hi);
            }
            t0 = t0.max(lo);
            t1 = t1.min(hi);
            if t0 > t1 {
                return None;
            }
        }
        Some((t0, t1))
    }

    /// Area in square metres.
    pub fn area(&self) -> f64 {
        self.length * self.width
    }

    /// Axis-aligned bounds `(min, max)`.
    pub fn bounds(&self) -> (P2, P2) {
        let c = self.corners();
        let mut lo = c[0];
        let mut hi = c[0];
        for p in &c[1..] {
            lo = P2::new(lo.x.min(p.x), lo.y.min(p.y));
            hi = P2::new(hi.x.max(p.x), hi.y.max(p.y));
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const EPS: f64 = 1e-12;

    fn p(x: f64, y: f64) -> P2 {
        P2::new(x, y)
    }

    #[test]
    fn axis_aligned_box_known_answers() {
        // 4 x 2 box at the origin, r = 0.
        let f = Footprint::from_aerialist(0.0, 0.0, 4.0, 2.0, 0.0);
        assert_eq!(f.distance_to_point(p(5.0, 0.0)), 3.0);
        assert_eq!(f.distance_to_point(p(0.0, 4.0)), 3.0);
        assert!((f.distance_to_point(p(5.0, 5.0)) - (9.0f64 + 16.0).sqrt()).abs() < EPS);
        assert_eq!(f.distance_to_point(p(0.5, 0.5)), 0.0, "a point inside");
        // A segment crossing the box.
        assert_eq!(f.distance_to_segment(p(-5.0, 0.0), p(5.0, 0.0)), 0.0);
        // A segment parallel to the long side, 3 m away.
        assert!((f.distance_to_segment(p(-10.0, 4.0), p(10.0, 4.0)) - 3.0).abs() < EPS);
        // An end point nearest: segment pointing away from the box.
        assert!((f.distance_to_segment(p(4.0, 0.0), p(10.0, 3.0)) - 2.0).abs() < EPS);
    }

    #[test]
    fn rotated_90_swaps_sides() {
        let f = Footprint::from_aerialist(1.0, 1.0, 4.0, 2.0, 90.0);
        assert!((f.distance_to_point(p(1.0, 4.0)) - 1.0).abs() < EPS);
        assert!((f.distance_to_point(p(4.0, 1.0)) - 2.0).abs() < EPS);
    }

    #[test]
    fn rotated_45_corner_on_axis() {
        // A 2 x 2 square turned 45 deg has its corners at distance sqrt(2) on the axes.
        let f = Footprint::from_aerialist(0.0, 0.0, 2.0, 2.0, 45.0);
        let r2 = 2.0f64.sqrt();
        assert!((f.distance_to_point(p(3.0, 0.0)) - (3.0 - r2)).abs() < 1e-12);
        // A segment along the diagonal direction x + y = 3 lies 3/sqrt(2) - 1 from the square's side.
        let d = f.distance_to_segment(p(3.0, 0.0), p(0.0, 3.0));
        assert!((d - (3.0 / r2 - 1.0)).abs() < 1e-12, "{d}");
    }

    #[test]
    fn rotated_30_known_answer() {
        // 6 x 2 box turned 30 deg: a point 4 m along its axis and 2 m to its side.
        let f = Footprint::from_aerialist(10.0, -3.0, 6.0, 2.0, 30.0);
        let (u, v) = f.axes();
        let q = f.center + u * 4.0 + v * 2.0;
        assert!((f.distance_to_point(q) - 2.0f64.sqrt()).abs() < 1e-12);
        assert!(!f.contains(q));
        assert!(f.contains(f.center + u * 2.9 + v * 0.9));
    }

    #[test]
    fn clip_segment_through_box() {
        let f = Footprint::from_aerialist(0.0, 0.0, 2.0, 2.0, 0.0);
        let (t0, t1) = f.clip_segment(p(-2.0, 0.0), p(2.0, 0.0)).expect("crosses");
        assert!((t0 - 0.25).abs() < EPS && (t1 - 0.75).abs() < EPS);
        assert!(f.clip_segment(p(-2.0, 3.0), p(2.0, 3.0)).is_none());
    }
}
