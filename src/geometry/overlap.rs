//! Relations between two footprints: gap, overlap, intersection area and the competition's IoU.

use super::P2;
use super::footprint::Footprint;
use super::segment::segments_intersect;

/// Gap between two footprints in metres; 0 when they overlap, touch or one holds the other.
pub fn footprint_distance(a: &Footprint, b: &Footprint) -> f64 {
    let (ca, cb) = (a.corners(), b.corners());
    if ca.iter().any(|p| b.contains(*p)) || cb.iter().any(|p| a.contains(*p)) {
        return 0.0;
    }
    for (p, q) in a.edges() {
        for (r, s) in b.edges() {
            if segments_intersect(p, q, r, s) {
                return 0.0;
            }
        }
    }
    // Disjoint convex polygons: the closest pair involves a corner of one of them.
    let from_a = ca.iter().map(|p| b.distance_to_point(*p));
    let from_b = cb.iter().map(|p| a.distance_to_point(*p));
    from_a.chain(from_b).fold(f64::INFINITY, f64::min)
}

/// Whether two footprints overlap or touch, with `tolerance_m` of slack (a gap up to it counts as touching).
pub fn footprints_touch_or_overlap(a: &Footprint, b: &Footprint, tolerance_m: f64) -> bool {
    footprint_distance(a, b) <= tolerance_m
}

/// Area of the intersection of two footprints (square metres), by convex polygon clipping.
pub fn intersection_area(a: &Footprint, b: &Footprint) -> f64 {
    let mut poly: Vec<P2> = a.corners().to_vec();
    // Clip `a` by each edge of `b` (corners are counter-clockwise, so inside is on the left).
    for (p, q) in b.edges() {
        if poly.is_empty() {
            return 0.0;
        }
        let side = |x: P2| (q - p).perp(&(x - p));
        let mut out = Vec::with_capacity(poly.len() + 2);
        for i in 0..poly.len() {
            let cur = poly[i];
            let next = poly[(i + 1) % poly.len()];
            let (sc, sn) = (side(cur), side(next));
            if sc >= 0.0 {
                out.push(cur);
            }
            if (sc >= 0.0) != (sn >= 0.0) {
                let t = sc / (sc - sn);
                out.push(cur + (next - cur) * t);
            }
        }
        poly = out;
    }
    polygon_area(&poly)
}

fn polygon_area(poly: &[P2]) -> f64 {
    let n = poly.len();
    if n < 3 {
        return 0.0;
    }
    let twice: f64 = (0..n).map(|i| poly[i].coords.perp(&poly[(i + 1) % n].coords)).sum();
    (twice / 2.0).abs()
}

/// Intersection over union of two sets of footprints, the competition's similarity of two tests.
///
/// Exact when the footprints within each set do not overlap one another, which every valid test
/// guarantees (the rules forbid overlapping obstacles). Two empty sets are identical (1.0).
pub fn union_iou(a: &[Footprint], b: &[Footprint]) -> f64 {
    let area_a: f64 = a.iter().map(Footprint::area).sum();
    let area_b: f64 = b.iter().map(Footprint::area).sum();
    let inter: f64 = a
        .iter()
        .flat_map(|fa| b.iter().map(move |fb| intersection_area(fa, fb)))
        .sum();
    let union = area_a + area_b - inter;
    if union <= 0.0 {
        1.0
    } else {
        (inter / union).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fp(x: f64, y: f64, l: f64, w: f64, r: f64) -> Footprint {
        Footprint::from_aerialist(x, y, l, w, r)
    }

    #[test]
    fn gap_overlap_and_touch() {
        let a = fp(0.0, 0.0, 2.0, 2.0, 0.0);
        assert!((footprint_distance(&a, &fp(5.0, 0.0, 2.0, 2.0, 0.0)) - 3.0).abs() < 1e-12);
        assert_eq!(footprint_distance(&a, &fp(2.0, 0.0, 2.0, 2.0, 0.0)), 0.0, "touching");
        assert_eq!(footprint_distance(&a, &fp(0.5, 0.5, 2.0, 2.0, 0.0)), 0.0, "overlap");
        assert_eq!(footprint_distance(&a, &fp(0.0, 0.0, 0.5, 0.5, 10.0)), 0.0, "inside");
        // A cross: neither holds a corner of the other, the edges cross.
        assert_eq!(
            footprint_distance(&fp(0.0, 0.0, 10.0, 1.0, 0.0), &fp(0.0, 0.0, 1.0, 10.0, 0.0)),
            0.0
        );
        assert!(footprints_touch_or_overlap(&a, &fp(2.0, 0.0, 2.0, 2.0, 0.0), 0.0));
    }

    #[test]
    fn intersection_areas() {
        let a = fp(0.0, 0.0, 2.0, 2.0, 0.0);
        assert!((intersection_area(&a, &a) - 4.0).abs() < 1e-12);
        assert!((intersection_area(&a, &fp(1.0, 1.0, 2.0, 2.0, 0.0)) - 1.0).abs() < 1e-12);
        assert_eq!(intersection_area(&a, &fp(5.0, 5.0, 2.0, 2.0, 0.0)), 0.0);
        // A square and itself turned 45 deg: a regular octagon of area 8 (sqrt 2 - 1).
        let oct = intersection_area(&a, &fp(0.0, 0.0, 2.0, 2.0, 45.0));
        assert!((oct - 8.0 * (2.0f64.sqrt() - 1.0)).abs() < 1e-12, "{oct}");
    }

    #[test]
    fn iou_of_sets() {
        let a = [fp(0.0, 0.0, 2.0, 2.0, 0.0)];
        let b = [fp(1.0, 0.0, 2.0, 2.0, 0.0)];
        assert!((union_iou(&a, &b) - 2.0 / 6.0).abs() < 1e-12);
        assert_eq!(union_iou(&a, &a), 1.0);
        assert_eq!(union_iou(&a, &[fp(10.0, 0.0, 2.0, 2.0, 0.0)]), 0.0);
    }
}
