//! `--obstacles TEST.yaml --crash-on-collision`: the test's boxes as a collision world.
//!
//! Boxes come from the foundation (`prgenuav::model::Obstacle`): footprint in local NED x/y,
//! solid from the ground up to `z + h` (height up). The vehicle position is local NED (z down).

use std::path::Path;

use prgenuav::geometry::{Footprint, P2};
use prgenuav::model::{ModelError, Obstacle, TestCase};

use crate::dynamics::Ned;
use crate::vehicle::CollisionWorld;

/// The obstacles of a test case.
#[derive(Debug, Clone)]
pub struct ObstacleWorld {
    boxes: Vec<(Footprint, f64)>,
}

impl ObstacleWorld {
    /// From obstacles (local NED footprints, heights up).
    pub fn new(obstacles: &[Obstacle]) -> Self {
        Self {
            boxes: obstacles.iter().map(|o| (o.footprint(), o.top_m())).collect(),
        }
    }

    /// Load a test-case YAML and keep its obstacles.
    pub fn from_test_file(path: &Path) -> Result<Self, ModelError> {
        Ok(Self::new(&TestCase::load(path)?.obstacles))
    }

    /// Number of boxes.
    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    /// True without boxes.
    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }
}

impl CollisionWorld for ObstacleWorld {
    fn collision(&self, pos_ned: &Ned) -> Option<String> {
        let height_up_m = -pos_ned.z;
        let p = P2::new(pos_ned.x, pos_ned.y);
        self.boxes
            .iter()
            .position(|(fp, top)| height_up_m <= *top && fp.contains(p))
            .map(|i| format!("collided with obstacle {i}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inside_below_top_collides() {
        let w = ObstacleWorld::new(&[Obstacle::new(10.0, 4.0, 20.0, 20.0, 0.0, 90.0)]);
        // Turned 90°: 10 m long along East, 4 m along North.
        assert!(w.collision(&Ned::new(20.0, 4.0, -5.0)).is_some());
        assert!(w.collision(&Ned::new(23.0, 0.0, -5.0)).is_none());
        assert!(w.collision(&Ned::new(20.0, 0.0, -21.0)).is_none(), "above the top");
        assert_eq!(w.len(), 1);
    }
}
