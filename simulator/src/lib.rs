//! prgenuav's own vehicle-and-world simulator: a multicopter (by default Gazebo Classic's iris, PX4's
//! reference quadrotor) with seeded sensors, feeding PX4 over the HIL protocol as Gazebo's and jMAVSim's
//! `simulator_mavlink` links do, and written from the physics.
//!
//! - [`vehicle`]: the rigid body (local NED world, body FRD), the rotors (Gazebo's motor model), the
//!   landing gear, the iris's figures.
//! - [`world`]: the standard atmosphere, the World Magnetic Model 2025, seeded wind and gusts.
//! - [`sensors`]: IMU every 4 ms step, magnetometer 100 Hz, barometer 50 Hz, GPS 5 Hz 120 ms late, each
//!   with Gazebo's noise and its own random stream of the one seed: the same seed and the same motor
//!   commands give the same sensor stream bit for bit.
//! - [`sim`]: one [`Simulation`] stepping them on one clock.
//! - [`hil`]: the messages, the lockstep policy, the TCP server PX4 SITL connects to, the serial link to a
//!   board on the wall clock with its UDP gateway, and the [`hil::gate`] for a host on simulated time.
//! - [`Simulator`]: the library face.
//!
//! # Running against PX4 SITL, with a host on simulated time
//!
//! ```no_run
//! # async fn run() -> Result<(), simulator::SimError> {
//! use std::time::Duration;
//! use simulator::hil::gate::{GateConfig, gate};
//! use simulator::hil::lockstep::LockstepConfig;
//! use simulator::{Cancel, SimConfig, Simulator};
//!
//! let (g, mut holds) = gate(GateConfig { period: Some(Duration::from_millis(100)), ..GateConfig::default() });
//! let mut sim = Simulator::new(SimConfig::default()).with_gate(g);
//! let clock = sim.clock(); // clock.now(): simulated time
//! let mut truth = sim.truth(); // truth.borrow(): position NED, velocity, attitude, rates, after each step
//! tokio::spawn(async move {
//!     while let Some(hold) = holds.next_hold().await {
//!         // every 100 ms of simulated time: PX4 waits while this runs
//!         let _ = hold.truth.position_ned_m;
//!     } // each hold is released when dropped
//! });
//! let cancel = Cancel::new();
//! let addr = "127.0.0.1:4560".parse().expect("address");
//! let report = sim.serve_sitl(addr, Duration::from_secs(60), &LockstepConfig::default(), &cancel).await?;
//! println!("real-time factor {:.1}", report.real_time_factor());
//! # Ok(()) }
//! ```
//!
//! The frames: local NED about the home (metres, z down, z = 0 resting on the ground), body FRD (x forward,
//! y right, z down); angles right-handed about those axes (yaw clockwise from North seen from above).

#![warn(missing_docs)]

pub mod cancel;
pub mod error;
pub mod hil;
pub mod noise;
pub mod runner;
pub mod sensors;
pub mod sim;
pub mod time;
pub mod vehicle;
pub mod world;

pub use cancel::Cancel;
pub use error::SimError;
pub use runner::Simulator;
pub use sim::{GroundTruth, SimConfig, Simulation};
pub use time::{STEP, SimClock, SimTime};
