//! The frames and the projection every prgenuav crate shares, so the product, the mock autopilot and the
//! vehicle simulator place a point on the Earth the same way.
//!
//! - [`geo`]: a WGS-84 position ([`GeoPoint`]), the competition's home ([`SIM_HOME`]) and PX4's
//!   azimuthal-equidistant projection about a home ([`LocalProjection`]: local North/East metres), with the
//!   great-circle distance PX4 uses for its mission checks ([`distance_m`]).
//! - [`frames`]: the local frames and their conversions, each named for its direction: local NED (PX4: x North,
//!   y East, z Down; body FRD), planner ENU (x East, y North, z Up), Gazebo's body FLU (x forward, y left,
//!   z up), and Aerialist's north-east-height.
//!
//! The projection is checked against hand-computed arc lengths and a waypoint of the competition's mission 2
//! as PX4 placed it, and property-tested for round trips; the crates that used to keep a copy of their own
//! (so a bug could not cancel out between the bridge and the mock) share this checked one instead.

pub mod frames;
pub mod geo;

pub use geo::{EARTH_RADIUS_M, GeoPoint, LocalProjection, SIM_HOME, distance_m};
