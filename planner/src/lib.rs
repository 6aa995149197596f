//! A faithful Rust port of the PX4-Avoidance 3DVFH* local planner (`docs/planner.md` §3-8) with a pure,
//! clock-free API: parameter structs in, values out, no messaging and no wall clock.
//!
//! It keeps the original's split: the point memory ([`cloud`]), the polar histogram ([`histogram`],
//! [`polar`]), the cost matrix and its smoothing ([`cost`], [`smoothing`], [`select`]), the star tree
//! ([`tree`]), one planning step ([`planner`]) and the waypoint generator ([`waypoint`]). The camera FOV it
//! plans with is [`fov`], optionally estimated from the clouds as the original does ([`fov_estimate`]).
//!
//! Every position, velocity and direction here is in the planner's **ENU** world frame (x East, y North, z Up,
//! metres, m/s). Angles are degrees unless named `_rad`.
#![warn(missing_docs)]

pub mod cloud;
pub mod cost;
pub mod fov;
pub mod fov_estimate;
pub mod histogram;
pub mod params;
pub mod planner;
pub mod polar;
pub mod select;
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
pub enum PlannerError {
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
