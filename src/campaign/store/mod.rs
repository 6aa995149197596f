//! What a campaign keeps on disk: its folder and the lock that gives it one writer, the journal of every
//! flight, and the trust boundary every folder read back goes through ([`trust`]).

pub mod folder;
pub mod journal;
mod journal_line;
mod journal_memory;
pub mod trust;
