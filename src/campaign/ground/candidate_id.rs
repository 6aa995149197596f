//! A candidate's identity, shared by every record of it from draw to written test.

use serde::{Deserialize, Serialize};

/// A candidate's identity in its campaign: its generator index for the campaign's seed (so the same seed draws
/// the same candidate under it), and its place in the campaign's list of candidates. Written as the bare
/// number in the journal and the reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize)]
#[serde(transparent)]
pub struct CandidateId(pub u64);

impl CandidateId {
    /// Its place in the campaign's list of candidates.
    pub fn index(self) -> usize {
        usize::try_from(self.0).unwrap_or(usize::MAX)
    }
}

impl std::fmt::Display for CandidateId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}
