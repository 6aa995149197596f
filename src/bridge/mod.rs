//! The MAVLink bridge: flies a test on PX4 (SITL or hardware) or the mock autopilot with the obstacles kept
//! virtual, and measures the true minimum distance from the vehicle's own position stream.
//!
//! Three groups, each importing only the ones below it (no import circle):
//! - [`session`]: one flight from connection to report ([`session::run`]): placement in the test's frame,
//!   setup, readiness, following the flight, the [`session::recorder`] and the [`session::report`].
//! - [`companion`]: planning while flying: the [`companion::avoidance`] companion (PX4's avoidance interface)
//!   and the [`companion::offboard`] pilot, both driving a [`companion::steer::Steer`] (the LFS planner in the
//!   test's frame, [`companion::frame`]).
//! - [`wire`]: the MAVLink protocol: [`wire::url`] (addresses), [`wire::link`] (one transport, a receive task
//!   fanning out, counters), socket-free state machines ([`wire::mission_upload`], [`wire::mission_download`],
//!   [`wire::params`], [`wire::command`]) run by [`wire::link::Link::exchange`], and the vehicle's state
//!   folded from its messages ([`wire::vehicle`]). Every timeout is in vehicle time ([`wire::clock`]), so a
//!   sped-up simulator keeps every timer in proportion.
//!
//! [`options`] and [`fly()`] sit on top. [`sitl`] starts PX4 SITL, [`hil`] runs prgenuav's iris simulator
//! beside a flight (PX4 SITL in external-simulator mode, or a board in HITL).
//!
//! ```no_run
//! # async fn demo(test: &prgenuav::model::TestCase) -> Result<(), prgenuav::bridge::BridgeError> {
//! use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, fly};
//! let opts = FlyOptions { connect: "udpin:0.0.0.0:14541".into(), mode: FlyMode::Mission, ..FlyOptions::default() };
//! let report = fly(test, &opts, CancelToken::new()).await?;
//! println!("{:?} {:?}", report.status, report.min_distance);
//! # Ok(()) }
//! ```

pub mod bench;
pub mod companion;
pub mod fly;
pub mod hil;
pub mod options;
pub mod px4_version;
pub mod session;
pub mod sitl;
pub mod wire;

pub use bench::Bench;
pub use companion::predict::{Prediction, predict};
pub use fly::{fly, fly_on};
pub use options::{BridgeError, FlyMode, FlyOptions, SimLink, VehicleSim};
pub use session::report::{FlightReport, Status};
pub use wire::cancel::CancelToken;
pub use wire::link::{LinkStats, Transport};
pub use wire::url::{DEFAULT_URL, LinkAddress, UrlError};
