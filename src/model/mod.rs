//! The competition's domain: missions, obstacles, the arena, tests and trajectories, read from and
//! written to the formats Aerialist uses.

mod anchor;
mod arena;
mod error;
mod fields;
pub mod geo;
mod mission;
mod obstacle;
mod tables;
mod test_case;
mod trajectory;
mod ulog;

pub use arena::{Arena, Range};
pub use error::{ModelError, Result};
pub use geo::{GeoPoint, LocalProjection, SIM_HOME};
pub use mission::{CMD_LAND, CMD_TAKEOFF, CMD_WAYPOINT, LocalPoint, Mission, MissionItem};
pub use obstacle::{Obstacle, Position, Size};
pub use tables::{Command, Param, parse_commands_csv, parse_params_csv};
pub use test_case::{Spelling, TestCase};
pub use trajectory::{AERIALIST_BIN_S, Sample, Trajectory};
pub use ulog::{load_flight, load_ulog_trajectory};
