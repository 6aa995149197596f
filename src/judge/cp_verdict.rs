//! Whether a Collision Prevention flight came inside `CP_DIST`: the closest the vehicle's centre came to a
//! box (3-D, the recorded positions in the test's frame), as Collision Prevention itself measures, beside
//! the competition's judged distance.

use serde::Serialize;

use crate::geometry::point_box_distance;
use crate::model::{Obstacle, Trajectory};

/// The Collision Prevention part of a flight's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CpVerdict {
    /// The `CP_DIST` flown, metres.
    pub cp_dist_m: f64,
    /// The closest the vehicle's centre came to a box, metres (`null` without positions or boxes).
    pub closest_centre_m: Option<f64>,
    /// Whether that is below `CP_DIST`: Collision Prevention did not keep its distance.
    pub inside_cp_dist: Option<bool>,
}

/// The verdict of `trajectory` against `obstacles` for `cp_dist_m`.
pub fn cp_verdict(trajectory: &Trajectory, obstacles: &[Obstacle], cp_dist_m: f64) -> CpVerdict {
    let solids: Vec<_> = obstacles.iter().map(Obstacle::solid).collect();
    let closest_centre_m = trajectory
        .samples
        .iter()
        .flat_map(|s| solids.iter().map(move |b| point_box_distance(b, [s.x, s.y, s.z])))
        .reduce(f64::min);
    CpVerdict {
        cp_dist_m,
        closest_centre_m,
        inside_cp_dist: closest_centre_m.map(|d| d < cp_dist_m),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Sample;

    #[test]
    fn inside_when_the_centre_came_closer_than_cp_dist() {
        let o = [Obstacle::new(2.0, 2.0, 20.0, 0.0, 5.0, 0.0)];
        let pass = |y: f64| Trajectory {
            samples: (0..=10)
                .map(|i| Sample {
                    t_s: f64::from(i),
                    x: f64::from(i) - 5.0,
                    y,
                    z: 5.0,
                    r: None,
                })
                .collect(),
        };
        let v = cp_verdict(&pass(2.5), &o, 2.0);
        assert!(
            (v.closest_centre_m.unwrap() - 1.5).abs() < 1e-5 && v.inside_cp_dist == Some(true),
            "{v:?}"
        );
        let v = cp_verdict(&pass(1.5), &o, 2.0);
        assert!(
            (v.closest_centre_m.unwrap() - 2.5).abs() < 1e-5 && v.inside_cp_dist == Some(false),
            "{v:?}"
        );
        assert_eq!(
            cp_verdict(&Trajectory { samples: vec![] }, &o, 2.0).inside_cp_dist,
            None
        );
    }
}
