//! The campaign's ground floor: the vocabulary every stage shares, importing no stage. A candidate and its
//! identity ([`candidate`], [`candidate_id`]), how a flight ended ([`flight_status`]), what a stage asks of the
//! low-fidelity simulator and of the progress display ([`screener`]), the wall time of each stage
//! ([`stage_times`]), the campaign's error ([`error`]) and what every stage reads ([`input`]).

pub mod candidate;
pub mod candidate_id;
pub mod error;
pub mod flight_status;
pub mod input;
pub mod screener;
pub mod stage_times;
