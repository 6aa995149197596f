//! prgenuav's own iris simulator ([`simulator`]) beside a flight: PX4 SITL in external-simulator mode fed
//! by it in this process (`--sim iris`: [`sitl`]), over TCP in lockstep with the avoidance companion on
//! simulated time ([`gate`]) or over a serial pty on the wall clock ([`pty`]), and a flight controller on a
//! bench fed over its serial port, flown through the simulator's gateway (`--hitl`: [`board`]). [`run`] is
//! the simulator's task of one flight.

pub mod board;
pub mod gate;
pub mod pty;
pub mod run;
pub mod sitl;
