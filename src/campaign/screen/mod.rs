//! The low-fidelity screening of candidates: what a stage asks of the LFS ([`screener`]), the LFS's answer
//! ([`lfs_screener`]), and the screening and ensemble stages with their caches ([`stages`]), on every core.

pub mod cp_screener;
pub mod lfs_screener;
pub mod parallel;
pub mod screener;
pub mod stages;
