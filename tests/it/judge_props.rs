//! Property tests of the judge's height check: a level flight is above a box's top exactly when it flies
//! higher than the box, by exactly the difference, in either edition.

use prgenuav::judge::{Judge, judge_in_frame};
use prgenuav::model::{Obstacle, Sample, Trajectory};
use proptest::prelude::*;

fn obstacle() -> impl Strategy<Value = Obstacle> {
    (
        2.0f64..20.0,
        2.0f64..20.0,
        5.0f64..25.0,
        -20.0f64..20.0,
        0.0f64..40.0,
        0.0f64..90.0,
    )
        .prop_map(|(l, w, h, x, y, r)| Obstacle::new(l, w, h, x, y, r))
}

/// A straight flight at `z` metres from `a` to `b` (x North, y East), 10 samples a second over 20 s.
fn level(a: (f64, f64), b: (f64, f64), z: f64) -> Trajectory {
    Trajectory::new(
        (0..=200)
            .map(|i| {
                let t = f64::from(i) / 200.0;
                Sample {
                    t_s: 20.0 * t,
                    x: a.0 + (b.0 - a.0) * t,
                    y: a.1 + (b.1 - a.1) * t,
                    z,
                    r: None,
                }
            })
            .collect(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]

    #[test]
    fn a_level_flight_is_above_the_top_exactly_when_higher_than_the_box(
        o in obstacle(),
        a in (-40.0f64..40.0, -10.0f64..60.0),
        b in (-40.0f64..40.0, -10.0f64..60.0),
        z in 1.0f64..30.0,
        edition in prop::sample::select(Judge::ALL.to_vec()),
    ) {
        prop_assume!((z - o.size.h).abs() > 1e-6);
        let j = judge_in_frame(&level(a, b, z), &[o], edition).expect("a flight and a box");
        match j.above_top {
            Some(above) => {
                prop_assert!(z > o.size.h, "above at {z} over a {} m box", o.size.h);
                prop_assert_eq!(above.obstacle, 0);
                prop_assert!((above.height_m - (z - o.size.h)).abs() < 1e-9);
                prop_assert!(!j.collision, "above a box is not inside it");
            }
            None => prop_assert!(z < o.size.h, "not flagged at {z} over a {} m box", o.size.h),
        }
    }
}
