//! `--obstacles TEST.yaml --crash-on-collision`: the test's boxes as a collision world.
//!
//! Read with the mock's own minimal reader of Aerialist's `simulation.obstacles` (footprint centre `x` North,
//! `y` East, `l` x `w` turned `r` degrees from +x towards +y, solid from `z` up to `z + h`), independent of
//! the prgenuav library so the reference vehicle shares no code with the tool it tests.

use std::path::Path;

use serde::Deserialize;

use crate::dynamics::Ned;
use crate::vehicle::CollisionWorld;

#[derive(Debug, Clone, Copy, Deserialize)]
struct Size {
    l: f64,
    w: f64,
    h: f64,
}

#[derive(Debug, Clone, Copy, Deserialize)]
struct Position {
    x: f64,
    y: f64,
    #[serde(default)]
    z: f64,
    #[serde(default)]
    r: f64,
}

#[derive(Debug, Clone, Copy, Deserialize)]
struct BoxSpec {
    size: Size,
    position: Position,
}

#[derive(Debug, Deserialize)]
struct Simulation {
    #[serde(default)]
    obstacles: Vec<BoxSpec>,
}

#[derive(Debug, Deserialize)]
struct TestFile {
    simulation: Option<Simulation>,
}

/// A box in the local frame: centre, half sides along its own axes, rotation, vertical extent (height up).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidBox {
    /// Centre, metres North.
    pub x: f64,
    /// Centre, metres East.
    pub y: f64,
    /// Side along the box's x axis, metres.
    pub l: f64,
    /// Side along the box's y axis, metres.
    pub w: f64,
    /// Rotation from +x (North) towards +y (East), degrees.
    pub r_deg: f64,
    /// Base height, metres up.
    pub bottom_m: f64,
    /// Top height, metres up.
    pub top_m: f64,
}

impl SolidBox {
    /// Whether the NED position (z down) is inside or on the box.
    pub fn contains(&self, pos: &Ned) -> bool {
        let up = -pos.z;
        if up < self.bottom_m || up > self.top_m {
            return false;
        }
        let (s, c) = self.r_deg.to_radians().sin_cos();
        let (dx, dy) = (pos.x - self.x, pos.y - self.y);
        // Coordinates along the box's own axes.
        let (u, v) = (dx * c + dy * s, -dx * s + dy * c);
        u.abs() <= self.l / 2.0 && v.abs() <= self.w / 2.0
    }
}

/// The obstacles of a test case.
#[derive(Debug, Clone, Default)]
pub struct ObstacleWorld {
    boxes: Vec<SolidBox>,
}

impl ObstacleWorld {
    /// From boxes.
    pub fn new(boxes: Vec<SolidBox>) -> Self {
        Self { boxes }
    }

    /// Reads `simulation.obstacles` of a test YAML (other keys are ignored).
    pub fn from_test_file(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        let file: TestFile =
            serde_saphyr::from_str(&text).map_err(|e| format!("{}: not a test YAML: {e}", path.display()))?;
        let specs = file.simulation.map(|s| s.obstacles).unwrap_or_default();
        let mut boxes = Vec::with_capacity(specs.len());
        for (i, b) in specs.iter().enumerate() {
            let nums = [
                b.size.l,
                b.size.w,
                b.size.h,
                b.position.x,
                b.position.y,
                b.position.z,
                b.position.r,
            ];
            if nums.iter().any(|v| !v.is_finite()) || b.size.l <= 0.0 || b.size.w <= 0.0 || b.size.h <= 0.0 {
                return Err(format!(
                    "{}: simulation.obstacles[{i}]: sizes must be positive, numbers finite",
                    path.display()
                ));
            }
            boxes.push(SolidBox {
                x: b.position.x,
                y: b.position.y,
                l: b.size.l,
                w: b.size.w,
                r_deg: b.position.r,
                bottom_m: b.position.z,
                top_m: b.position.z + b.size.h,
            });
        }
        Ok(Self { boxes })
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
        self.boxes
            .iter()
            .position(|b| b.contains(pos_ned))
            .map(|i| format!("collided with obstacle {i}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn world() -> ObstacleWorld {
        let b = SolidBox {
            x: 20.0,
            y: 0.0,
            l: 10.0,
            w: 4.0,
            r_deg: 90.0,
            bottom_m: 0.0,
            top_m: 20.0,
        };
        ObstacleWorld::new(vec![b])
    }

    #[test]
    fn inside_below_top_collides() {
        let w = world();
        // Turned 90 degrees: 10 m long along East, 4 m along North.
        assert!(w.collision(&Ned::new(20.0, 4.0, -5.0)).is_some());
        assert!(w.collision(&Ned::new(23.0, 0.0, -5.0)).is_none());
        assert!(w.collision(&Ned::new(20.0, 0.0, -21.0)).is_none(), "above the top");
        assert_eq!(w.len(), 1);
    }

    #[test]
    fn reads_a_test_yaml() {
        let dir = std::env::temp_dir().join(format!("mock-obstacles-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.yaml");
        let yaml = "robot:\n  mission_file: x.plan\nsimulation:\n  obstacles:\n  - size: {l: 10, w: 4, h: 20}\n    \
                    position: {x: 20, y: 0, z: 0, r: 90}\n";
        std::fs::write(&path, yaml).unwrap();
        let w = ObstacleWorld::from_test_file(&path).unwrap();
        assert!(w.collision(&Ned::new(20.0, 4.0, -5.0)).is_some());
        std::fs::write(
            &path,
            "simulation:\n  obstacles:\n  - size: {l: -1, w: 4, h: 20}\n    position: {x: 0, y: 0}\n",
        )
        .unwrap();
        assert!(ObstacleWorld::from_test_file(&path).unwrap_err().contains("positive"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
