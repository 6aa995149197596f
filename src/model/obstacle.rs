//! A box obstacle as Aerialist writes it: size and centre position, angle in degrees.

use serde::{Deserialize, Serialize};

use crate::geometry::{Box3, Footprint};

/// Box dimensions in metres: `l` along the box's own x axis, `w` along its y axis, `h` up.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Size {
    /// Length, metres.
    pub l: f64,
    /// Width, metres.
    pub w: f64,
    /// Height, metres.
    pub h: f64,
}

/// Where a box stands, in Aerialist's frame (PX4 local NED on the ground: `x` North, `y` East, metres).
///
/// `x, y` is the centre of the footprint, `z` the base height (0 on the ground), `r` the rotation in
/// **degrees**, counter-clockwise from +x towards +y about the centre.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Position {
    /// North of the centre, metres.
    pub x: f64,
    /// East of the centre, metres.
    pub y: f64,
    /// Base height, metres (0 = on the ground).
    pub z: f64,
    /// Rotation, degrees, from +x towards +y.
    pub r: f64,
}

/// A box obstacle of a test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Obstacle {
    /// Dimensions.
    pub size: Size,
    /// Placement.
    pub position: Position,
}

impl Obstacle {
    /// A box of `l x w x h` metres centred at `(x, y)` on the ground, turned `r_deg` degrees.
    pub fn new(l: f64, w: f64, h: f64, x: f64, y: f64, r_deg: f64) -> Self {
        Self {
            size: Size { l, w, h },
            position: Position { x, y, z: 0.0, r: r_deg },
        }
    }

    /// The footprint rectangle on the ground.
    pub fn footprint(&self) -> Footprint {
        Footprint::from_aerialist(
            self.position.x,
            self.position.y,
            self.size.l,
            self.size.w,
            self.position.r,
        )
    }

    /// The solid box, from the ground to its top (`z + h`).
    pub fn solid(&self) -> Box3 {
        Box3::new(&self.footprint(), self.position.z + self.size.h)
    }

    /// Height of the top face above the ground, metres.
    pub fn top_m(&self) -> f64 {
        self.position.z + self.size.h
    }
}
