//! The high-fidelity flights: the vehicle trait and the jobs it flies ([`vehicle`]), the fleet that flies a
//! queue of jobs on all vehicles and journals each ([`fleet`]), the flight stage ([`stage`]), confirmation
//! re-flights ([`confirm`]), and the backends: embedded mock and MAVLink ([`mock_mavlink`]), PX4 SITL
//! ([`px4`], [`px4_iris`]), boards in the loop ([`hitl`]) and jobs on an engine ([`runner`]).

pub mod backend;
pub mod confirm;
pub mod fleet;
pub mod hitl;
pub mod mock_mavlink;
pub mod px4;
pub mod px4_iris;
mod px4_leaves;
pub mod retry;
pub mod runner;
pub mod stage;
pub mod vehicle;
