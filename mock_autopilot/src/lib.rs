//! A PX4-like MAVLink vehicle for tests without hardware: mission, fence, parameter and command
//! protocols as PX4 implements them, multirotor kinematics, telemetry, time scaling and faults.
//!
//! ```no_run
//! # async fn demo() -> Result<(), mock_autopilot::MockError> {
//! use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
//! let mock = MockAutopilot::builder()
//!     .link(LinkSpec::UdpIn("127.0.0.1:0".parse().unwrap()))
//!     .speed_factor(SpeedFactor::Times(20.0))
//!     .spawn()
//!     .await?;
//! let port = mock.local_addr().unwrap().port(); // connect with udpout:127.0.0.1:{port}
//! mock.shutdown().await?;
//! # let _ = port; Ok(()) }
//! ```
#![warn(missing_docs)]

pub mod avoidance;
pub mod clock;
pub mod collision_prevention;
pub mod commands;
pub mod dynamics;
pub mod fence;
pub mod gusts;
pub mod land_detector;
pub mod link;
pub mod manual;
pub mod messages;
pub mod mission_items;
pub mod mission_server;
pub mod modes;
pub mod nav_items;
pub mod navigator;
pub mod obstacle_map;
pub mod obstacles;
pub mod offboard;
pub mod params;
pub mod posctl;
pub mod position_mode;
pub mod preflight;
pub mod range_scan;
pub mod release;
pub mod safety;
pub mod scenarios;
pub mod server;
pub mod status_text;
pub mod stick_lockstep;
pub mod sticks;
pub mod telemetry;
pub mod transport;
pub mod vehicle;

pub use clock::SpeedFactor;
pub use dynamics::Ned;
pub use link::Faults;
pub use modes::FlightMode;
pub use params::ParamValue;
pub use server::{Builder, LinkSpec, MockAutopilot, MockError, MockHandle};
pub use vehicle::{CollisionWorld, Vehicle, VehicleConfig, VehicleState};
