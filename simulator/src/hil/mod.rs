//! The HIL link to PX4: the messages, the lockstep policy, the gate for a host on simulated time, and the
//! transports (TCP lockstep for SITL, a serial port on the wall clock for a board, with its UDP gateway).

pub mod gate;
pub mod gateway;
pub mod link;
pub mod lockstep;
pub mod messages;
pub mod serial;
pub mod stepper;
pub mod tcp;
