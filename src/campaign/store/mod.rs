//! What a campaign keeps on disk: its folder and the lock that gives it one writer, the journal of every
//! flight, and the replay that lets a resumed campaign take the journaled flights instead of flying them.

pub mod folder;
pub mod journal;
mod journal_line;
mod journal_memory;
pub mod replay;
pub mod trust;
