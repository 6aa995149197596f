//! The competition's two definitions of a flight's distance to an obstacle ("judge editions").
//!
//! - `2025`: Aerialist's `Obstacle.distance` on the bare path: the 2-D distance from the box's footprint to
//!   the path as a polyline, and the height gap when the path passes over the box.
//! - `2026` (current): Aerialist's `Trajectory.min_distance_to_obstacles` measures from the path buffered by half
//!   the vehicle width (shapely `to_thick_line`, `VEHICLE_WIDTH` 0.25 m). The buffer is a 2-D polygon, so the
//!   distance is purely horizontal (no height-gap rule) and `VEHICLE_WIDTH / 2` less than the bare path's.
//!
//! A buffer by `r` is the Minkowski sum with a disc of radius `r`, so the distance from a convex footprint
//! to the buffered path is exactly `max(0, d - r)` for the bare 2-D distance `d`.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::model::competition::HALF_VEHICLE_WIDTH_M;

/// Which edition's definition judges a flight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum Judge {
    /// The bare path, 2-D footprint distance with the height-gap rule.
    #[serde(rename = "2025")]
    E2025,
    /// The path buffered by half the vehicle width, purely horizontal (the current edition).
    #[default]
    #[serde(rename = "2026")]
    E2026,
}

impl Judge {
    /// Both editions, oldest first.
    pub const ALL: [Judge; 2] = [Judge::E2025, Judge::E2026];

    /// The edition's year, as written on the command line and in JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Judge::E2025 => "2025",
            Judge::E2026 => "2026",
        }
    }

    /// The definition in one line, for reports.
    pub fn description(self) -> &'static str {
        match self {
            Judge::E2025 => {
                "2-D distance from each box's footprint to the bare path (height gap when the path passes over a box)"
            }
            Judge::E2026 => {
                "2-D distance from each box's footprint to the path buffered by half the vehicle width (0.125 m), \
                 horizontal only"
            }
        }
    }

    /// How this edition judges a vehicle that came closest to a box above its top.
    pub fn above_top_rule(self) -> &'static str {
        match self {
            Judge::E2025 => {
                "the 2025 judge measures horizontally beside a box, and counts the height gap only straight over a box"
            }
            Judge::E2026 => {
                "the 2026 judge is horizontal only and scores a crossing over a box 0 m, whatever its height"
            }
        }
    }

    /// The judged distance from the bare path's 2-D distance `d2d` to a box of height `box_h` (metres); `over`
    /// gives the lowest height of the path over the footprint (only asked when `d2d` is 0 in 2025).
    pub fn from_bare(self, d2d: f64, box_h: f64, over: impl FnOnce() -> Option<f64>) -> f64 {
        match self {
            Judge::E2025 if d2d > 0.0 => d2d,
            Judge::E2025 => match over() {
                Some(z) if z > box_h => z - box_h,
                _ => 0.0,
            },
            Judge::E2026 => (d2d - HALF_VEHICLE_WIDTH_M).max(0.0),
        }
    }
}

impl fmt::Display for Judge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

impl FromStr for Judge {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "2025" => Ok(Judge::E2025),
            "2026" => Ok(Judge::E2026),
            other => Err(format!("unknown judge edition {other:?} (use 2025 or 2026)")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn editions_parse_print_and_default_to_the_current_one() {
        assert_eq!(Judge::default(), Judge::E2026);
        for j in Judge::ALL {
            assert_eq!(j.as_str().parse::<Judge>(), Ok(j));
            assert_eq!(serde_json::to_value(j).unwrap(), j.as_str());
            assert!(!j.description().is_empty());
        }
        let e = "2024".parse::<Judge>().unwrap_err();
        assert!(e.contains("2025 or 2026"), "{e}");
    }

    #[test]
    fn buffered_path_is_half_a_vehicle_closer_and_ignores_height() {
        let never = || -> Option<f64> { panic!("2026 has no height rule") };
        assert!((Judge::E2026.from_bare(1.0, 5.0, never) - 0.875).abs() < 1e-12);
        assert_eq!(Judge::E2026.from_bare(0.1, 5.0, never), 0.0);
        assert_eq!(Judge::E2026.from_bare(0.0, 5.0, never), 0.0);
        assert_eq!(Judge::E2025.from_bare(1.0, 5.0, || None), 1.0);
        assert_eq!(Judge::E2025.from_bare(0.0, 5.0, || Some(8.0)), 3.0);
        assert_eq!(Judge::E2025.from_bare(0.0, 5.0, || Some(4.0)), 0.0);
    }
}
