//! What every stage of one campaign run reads, the same from the first stage to the last.

use std::path::Path;
use std::sync::atomic::AtomicBool;

use super::screener::{Progress, Screener};
use crate::campaign::settings::CampaignSettings;
use crate::model::TestCase;

/// What a campaign run reads that stays the same from its first stage to its last.
pub struct CampaignInput<'a> {
    /// Settings.
    pub cfg: &'a CampaignSettings,
    /// The campaign folder.
    pub folder: &'a Path,
    /// The case study.
    pub case: &'a TestCase,
    /// The LFS.
    pub screener: &'a dyn Screener,
    /// Progress output.
    pub progress: &'a dyn Progress,
    /// Stops the campaign.
    pub cancel: &'a AtomicBool,
}
