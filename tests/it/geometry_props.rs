//! Property tests of the exact geometry: non-negative, zero exactly on contact, invariant under rigid motion.

use prgenuav::geometry::{Footprint, P2, V2, footprint_distance, segments_intersect};
use proptest::prelude::*;

fn footprint() -> impl Strategy<Value = Footprint> {
    (
        -30.0f64..30.0,
        -30.0f64..30.0,
        0.5f64..20.0,
        0.5f64..20.0,
        0.0f64..360.0,
    )
        .prop_map(|(x, y, l, w, r)| Footprint::from_aerialist(x, y, l, w, r))
}

fn point() -> impl Strategy<Value = P2> {
    (-60.0f64..60.0, -60.0f64..60.0).prop_map(|(x, y)| P2::new(x, y))
}

/// Rotates by `a` radians about the origin, then translates by `t`.
fn motion(p: P2, a: f64, t: V2) -> P2 {
    let (s, c) = a.sin_cos();
    P2::new(c * p.x - s * p.y, s * p.x + c * p.y) + t
}

fn moved(f: &Footprint, a: f64, t: V2) -> Footprint {
    Footprint {
        center: motion(f.center, a, t),
        yaw_rad: f.yaw_rad + a,
        ..*f
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn segment_distance_is_never_negative_and_zero_exactly_on_contact(f in footprint(), a in point(), b in point()) {
        let d = f.distance_to_segment(a, b);
        prop_assert!(d >= 0.0);
        let touches = f.contains(a) || f.contains(b) || f.edges().iter().any(|(c, e)| segments_intersect(a, b, *c, *e));
        prop_assert_eq!(d == 0.0, touches);
        // Never more than the end points' distances, never less than a dense sampling's minimum minus slack.
        prop_assert!(d <= f.distance_to_point(a).min(f.distance_to_point(b)) + 1e-12);
        let sampled = (0..=200).map(|i| f.distance_to_point(a + (b - a) * (i as f64 / 200.0))).fold(f64::INFINITY, f64::min);
        prop_assert!(d <= sampled + 1e-9);
        prop_assert!(sampled - d <= (b - a).norm() / 200.0 + 1e-9, "d {} sampled {}", d, sampled);
    }

    #[test]
    fn distances_are_invariant_under_rotation_and_translation(
        f in footprint(), g in footprint(), a in point(), b in point(),
        angle in -7.0f64..7.0, tx in -100.0f64..100.0, ty in -100.0f64..100.0,
    ) {
        let t = V2::new(tx, ty);
        let (fm, gm) = (moved(&f, angle, t), moved(&g, angle, t));
        let (am, bm) = (motion(a, angle, t), motion(b, angle, t));
        prop_assert!((f.distance_to_segment(a, b) - fm.distance_to_segment(am, bm)).abs() < 1e-7);
        prop_assert!((f.distance_to_point(a) - fm.distance_to_point(am)).abs() < 1e-7);
        prop_assert!((footprint_distance(&f, &g) - footprint_distance(&fm, &gm)).abs() < 1e-7);
    }

    #[test]
    fn footprint_distance_is_symmetric_and_zero_exactly_on_overlap(f in footprint(), g in footprint()) {
        let d = footprint_distance(&f, &g);
        prop_assert!(d >= 0.0);
        prop_assert!((d - footprint_distance(&g, &f)).abs() < 1e-12);
        let overlap = prgenuav::geometry::intersection_area(&f, &g) > 1e-9;
        if overlap { prop_assert_eq!(d, 0.0); }
        if d > 1e-9 { prop_assert!(!overlap); }
        // The gap is at most the distance between any corner pair.
        let corner_min = f.corners().iter().flat_map(|p| g.corners().map(|q| (p - q).norm())).fold(f64::INFINITY, f64::min);
        prop_assert!(d <= corner_min + 1e-12);
    }
}
