//! Exact 2-D and 3-D geometry for obstacle footprints and flown paths.
//!
//! Everything here works in the competition's local frame: PX4 local NED projected on the ground,
//! `x` = North, `y` = East, metres. Heights are metres above ground, positive up (Aerialist's convention).

mod boxes;
mod footprint;
mod overlap;
mod segment;

pub use boxes::{Box3, point_box_distance, segment_box_distance};
pub use footprint::Footprint;
pub use overlap::{footprint_distance, footprints_touch_or_overlap, intersection_area, union_iou};
pub use segment::{point_segment_distance, segment_segment_distance, segments_intersect};

/// A point on the ground plane: `x` North, `y` East, metres.
pub type P2 = nalgebra::Point2<f64>;
/// A vector on the ground plane: `x` North, `y` East, metres.
pub type V2 = nalgebra::Vector2<f64>;
