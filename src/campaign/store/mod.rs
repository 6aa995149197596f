//! What a campaign keeps on disk: its folder and the lock that gives it one writer, and the journal of every
//! flight.

pub mod folder;
pub mod journal;
pub mod journal_check;
mod journal_line;
mod journal_memory;
