//! How well the simulator predicts the competition's real flights, and how sure it is.
//!
//! [`recorded`] reads recorded flights, [`fidelity`] compares the simulator's minimum distances with theirs;
//! [`cv`] cross-validates the motion model's constants on them; [`ensemble`] turns perturbed repeats of one
//! flight into a failure probability, scored by [`calibration`]; [`px4_flights`] reads flights we flew in
//! PX4 SITL into the same form. This sits above the simulator and is never used by it.

pub mod calibration;
pub mod cv;
pub mod ensemble;
pub mod fidelity;
pub mod px4_flights;
pub mod recorded;
