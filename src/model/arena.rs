//! The obstacle-designated area (ODA) and the value ranges a valid test must respect.

use serde::{Deserialize, Serialize};

/// An inclusive-exclusive range of allowed values, `min..=max`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Range {
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
}

impl Range {
    /// `min..=max`.
    pub const fn new(min: f64, max: f64) -> Self {
        Self { min, max }
    }

    /// Whether `v` lies in `min..=max`.
    pub fn contains(&self, v: f64) -> bool {
        v >= self.min && v <= self.max
    }

    /// Midpoint.
    pub fn mid(&self) -> f64 {
        (self.min + self.max) / 2.0
    }
}

/// The competition's arena and rules (`docs/formats.md`, rules; the values are [`Arena::COMPETITION`]), in the
/// local frame (`x` North, `y` East).
///
/// The footprint of every obstacle must lie strictly inside `x` x `y` (the ODA). "Bottom" and "top" of the
/// arena are its `y` borders (`y.min`, `y.max`), "left" and "right" its `x` borders.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Arena {
    /// North extent of the ODA and range of obstacle centre `x`, metres.
    pub x: Range,
    /// East extent of the ODA and range of obstacle centre `y`, metres.
    pub y: Range,
    /// Allowed box length, metres.
    pub l: Range,
    /// Allowed box width, metres.
    pub w: Range,
    /// Allowed box height, metres.
    pub h: Range,
    /// Allowed rotation, degrees.
    pub r: Range,
    /// The mission's flight altitude, metres; boxes must be taller.
    pub flight_altitude_m: f64,
    /// Most obstacles per test.
    pub max_obstacles: usize,
}

impl Default for Arena {
    fn default() -> Self {
        Self::COMPETITION
    }
}

impl Arena {
    /// The ODA's middle line `x` (North), metres.
    pub fn middle_x(&self) -> f64 {
        self.x.mid()
    }
}
