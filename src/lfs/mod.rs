//! The low-fidelity simulator (LFS): flies a test with a virtual depth camera, the 3DVFH* port of
//! [`prgenuav_planner`] and a motion model, then judges the flight as the competition does.
//!
//! - sensing: [`camera`] (intrinsics and mounting), [`render`] (every pixel) and [`render_fast`] (the
//!   planner's cloud), with the camera tilt of [`attitude`];
//! - the vehicle: [`mission`] (the plan as the planner's goals), [`motion`] (how the vehicle follows a
//!   setpoint), [`geodesy::frames`] (our local NED to the planner's ENU);
//! - the loop: [`sim`] steps a world tick by tick, configured by [`sim_config`];
//! - [`eval`]: how well the simulator predicts real flights, and its failure probability from an ensemble.
//!
//! The planner's modules are re-exported under their former paths (`lfs::planner`, `lfs::waypoint`, ...), so
//! callers need not know the crate boundary. Every position, velocity and direction here is in the
//! planner's **ENU** world frame (x East, y North, z Up, metres, m/s); [`geodesy::frames`] converts from and to our
//! local NED. Angles are degrees unless named `_rad`.

pub mod attitude;
pub mod camera;
mod column_slopes;
pub mod cp_constraint;
pub mod cp_model;
pub mod cp_params;
pub mod cp_pilot;
pub mod delay;
pub mod eval;

pub mod mission;
pub mod motion;
pub mod range_sensor;
pub mod render;
pub mod render_fast;
pub mod sim;
pub mod sim_config;

#[cfg(test)]
mod fov_takeoff_tests;

pub use eval::{calibration, cv, ensemble, fidelity, px4_flights};
pub use prgenuav_planner::PlannerError as LfsError;
pub use prgenuav_planner::{
    CostParams, Fov, PlannerParams, cloud, cost, fov, fov_estimate, histogram, params, planner, polar, select,
    smoothing, tree, waypoint,
};
