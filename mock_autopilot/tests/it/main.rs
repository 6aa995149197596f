//! Integration tests: the mock on ephemeral UDP ports, flown by rust-mavlink and pymavlink clients.

mod client;
mod faults;
mod garbage;
mod python;
mod rust_client;
