//! What a campaign learns from its flights: the LFS calibrated to the vehicle ([`calibration`]), a kernel over
//! the flown tests ([`surrogate`]), the refit between rounds ([`refit`]) and where flights failed
//! ([`failure_counts`], a diagnostic).

pub mod calibration;
pub mod failure_counts;
pub mod refit;
pub mod surrogate;
