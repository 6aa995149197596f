//! The low-fidelity screening of candidates: the LFS's answer to what a stage asks
//! ([`crate::campaign::ground::screener`]) ([`lfs_screener`]), and the screening and ensemble stages with their caches ([`stages`]), on every core.

pub mod cp_screener;
pub mod lfs_screener;
pub mod parallel;
pub mod stages;
