//! Low-fidelity simulator core: a faithful Rust port of the PX4-Avoidance 3DVFH* local planner
//! (`../shared/docs/3dvfh.md` §3-8) with a pure, clock-free API.
//!
//! Every position, velocity and direction here is in the planner's **ENU** world frame (x East, y North, z Up,
//! metres, m/s); [`frames`] converts from and to our local NED. Angles are degrees unless named `_rad`.

pub mod attitude;
pub mod calibration;
pub mod camera;
pub mod cloud;
pub mod cost;
pub mod cv;
pub mod ensemble;
pub mod fidelity;
pub mod fov;
pub mod fov_estimate;
pub mod frames;
pub mod histogram;
pub mod mission;
pub mod motion;
pub mod params;
pub mod planner;
pub mod polar;
pub mod px4_flights;
pub mod render;
pub mod render_fast;
pub mod select;
pub mod sim;
pub mod sim_config;
pub mod smoothing;
pub mod tree;
pub mod waypoint;

#[cfg(test)]
mod equivalence_tests;
#[cfg(test)]
mod reference;

pub use fov::Fov;
pub use params::{CostParams, PlannerParams};

/// Errors of the planner API (bad input, never a panic).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LfsError {
    /// A parameter is out of range or not finite.
    #[error("invalid planner parameter {name} = {value}")]
    InvalidParam {
        /// Parameter name as in [`PlannerParams`].
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// An input value (pose, goal, time) is not finite or not usable.
    #[error("invalid planner input {name}: {detail}")]
    InvalidInput {
        /// Which input.
        name: &'static str,
        /// What is wrong with it.
        detail: String,
    },
}
