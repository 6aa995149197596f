//! A PX4-like MAVLink vehicle that standard clients can fly.
