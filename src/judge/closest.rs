//! Where the un-binned path came closest to an obstacle: on each segment, a ternary search for its closest
//! point (distance to a convex set is convex along a segment). A segment whose exact distance already lies
//! beyond the best found cannot hold the closest point and is not searched: the result is the same, and a
//! flight of 10^6 samples costs one distance per segment instead of 120.

use super::Judge;
use crate::geometry::{Footprint, P2};
use crate::model::{Obstacle, Sample};

use super::ClosestApproach;

/// Slack for the skip: a point searched on a segment is never closer than the segment by more than rounding.
const ROUNDING_M: f64 = 1e-9;

/// The closest approach of `path` to `obstacles` by `judge`'s definition.
pub(super) fn closest_approach(judge: Judge, obstacles: &[Obstacle], path: &[Sample]) -> ClosestApproach {
    let mut best = ClosestApproach {
        t_s: 0.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
        obstacle: 0,
        distance: f64::INFINITY,
    };
    // One sample is a segment of no length.
    let single: Vec<Sample> = path.iter().chain(path).copied().collect();
    let segments = if path.len() == 1 { single.as_slice() } else { path };
    for (k, o) in obstacles.iter().enumerate() {
        let f = o.footprint();
        for w in segments.windows(2) {
            let (a, b) = (w[0], w[1]);
            let bare = f.distance_to_segment(P2::new(a.x, a.y), P2::new(b.x, b.y));
            // The edition's value of any point of the segment is at least this.
            let lower = judge.from_bare(bare, o.size.h, || None);
            if lower - ROUNDING_M >= best.distance {
                continue;
            }
            let s = search(&f, a, b);
            let d = judge.from_bare(distance(&f, &s), o.size.h, || Some(s.z));
            if d < best.distance {
                best = ClosestApproach {
                    t_s: s.t_s,
                    x: s.x,
                    y: s.y,
                    z: s.z,
                    obstacle: k,
                    distance: d,
                };
            }
        }
    }
    best
}

fn distance(f: &Footprint, s: &Sample) -> f64 {
    f.distance_to_point(P2::new(s.x, s.y))
}

/// The point of segment `a`-`b` closest to `f`, by ternary search.
fn search(f: &Footprint, a: Sample, b: Sample) -> Sample {
    let lerp = |t: f64| Sample {
        t_s: a.t_s + (b.t_s - a.t_s) * t,
        x: a.x + (b.x - a.x) * t,
        y: a.y + (b.y - a.y) * t,
        z: a.z + (b.z - a.z) * t,
        r: None,
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
        if distance(f, &lerp(m1)) <= distance(f, &lerp(m2)) {
            hi = m2
        } else {
            lo = m1
        }
    }
    lerp((lo + hi) / 2.0)
}
