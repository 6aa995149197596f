//! A PX4-like MAVLink vehicle for tests without hardware: mission, fence, parameter and command
//! protocols as PX4 implements them, multirotor kinematics, telemetry, time scaling and faults.
#![warn(missing_docs)]

pub mod avoidance;
pub mod clock;
pub mod commands;
pub mod dynamics;
pub mod fence;
pub mod geo;
pub mod messages;
pub mod mission_items;
pub mod mission_server;
pub mod modes;
pub mod navigator;
pub mod params;
pub mod scenarios;
pub mod telemetry;
pub mod vehicle;

pub use clock::SpeedFactor;
pub use dynamics::Ned;
pub use modes::FlightMode;
pub use vehicle::{CollisionWorld, Vehicle, VehicleConfig, VehicleState};
