//! The low-fidelity screening of candidates: the LFS's answer to what a stage asks
//! ([`crate::campaign::ground::screener`]) ([`lfs_screener`]), and the screening and ensemble stages with their caches ([`stages`]), on every core.

pub mod cp_screener;
pub mod lfs_screener;
pub mod parallel;
pub mod stages;

use crate::bridge::FlyMode;
use crate::campaign::ground::screener::Screener;
use crate::campaign::settings::CampaignSettings;
use crate::lfs::sim::SimConfig;

/// The screener a campaign's mode calls for: the Collision Prevention model in that mode, else the 3DVFH* LFS
/// with the campaign's motion model, both judged by the campaign's edition.
pub fn screener_for(s: &CampaignSettings) -> Box<dyn Screener> {
    let judge = s.campaign.judge;
    match s.campaign.mode {
        FlyMode::CollisionPrevention => Box::new(cp_screener::CpScreener { judge }),
        _ => Box::new(lfs_screener::LfsScreener {
            config: SimConfig {
                motion: s.screening.motion.model(),
                judge,
                ..SimConfig::default()
            },
            ensemble: crate::lfs::ensemble::EnsembleParams::default(),
        }),
    }
}
