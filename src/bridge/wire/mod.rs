//! The MAVLink protocol as the bridge speaks it: addresses, the link and its counters, socket-free exchange
//! state machines (mission, parameters, commands), the vehicle's clock, and the vehicle's state folded from
//! its messages. Nothing here knows about planning or about a flight's steps.

pub mod cancel;
pub mod clock;
pub mod command;
pub mod command_batch;
pub mod exchange;
pub mod geo_view;
pub mod link;
pub mod mission_download;
pub mod mission_upload;
pub mod notices;
pub mod param_read;
pub mod params;
pub mod plan_items;
pub mod pose;
pub mod tcp_in;
pub mod text_chunks;
pub mod udp_in;
pub mod url;
pub mod vehicle;
