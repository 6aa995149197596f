//! The competition's domain: missions, obstacles, the arena, tests and trajectories, read from and
//! written to the formats Aerialist uses.

mod anchor;
mod arena;
pub mod competition;
mod error;
mod fields;
mod files;
pub mod limit;
mod mission;
mod obstacle;
mod references;
pub mod safe_files;
mod tables;
mod test_case;
mod trajectory;
mod ulog;
pub mod ulog_frames;

pub use arena::{Arena, Range};
pub use competition::AERIALIST_BIN_S;
pub use error::{ModelError, Result};
pub use files::{check_writable, write_atomic};
pub use geodesy::{GeoPoint, LocalProjection, SIM_HOME};
pub use limit::Limit;
pub use mission::{CMD_LAND, CMD_TAKEOFF, CMD_WAYPOINT, LocalPoint, Mission, MissionItem};
pub use obstacle::{Obstacle, Position, Size};
pub(crate) use references::resolve as resolve_reference;
pub use tables::{Command, Param, parse_commands_csv, parse_params_csv};
pub use test_case::{Spelling, TestCase};
pub use trajectory::{Sample, Trajectory};
pub use ulog::{load_flight, load_ulog_trajectory};

#[cfg(test)]
#[path = "damage_tests.rs"]
mod damage_tests;
