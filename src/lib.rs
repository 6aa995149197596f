//! prgenuav: finds obstacle layouts that make an autonomous drone fly dangerously close to obstacles.
//!
//! Data flows one way: [`model`] (missions, obstacles, tests) -> generator -> low-fidelity simulator
//! -> MAVLink bridge -> report. The binary `prgenuav` is a thin CLI over this library.
#![warn(missing_docs)]

pub mod bridge;
pub mod campaign;
pub mod generator;
pub mod geometry;
pub mod io;
pub mod judge;
pub mod lfs;
pub mod model;
pub mod plot;
pub mod rules;
