//! `generate --runner 'COMMAND' [--jobs N] [--job-timeout S]`: the settings every runner job shares, checked
//! before anything is drawn or flown.

use std::path::PathBuf;

use anyhow::bail;
use prgenuav::campaign::run::CampaignConfig;
use prgenuav::campaign::runner::{DEFAULT_JOB_TIMEOUT_S, RunnerSettings, Template};
use prgenuav::model::Spelling as ModelSpelling;

use super::Args;

/// The runner's settings, checked before the campaign claims its folder (`campaign_folder` is set then).
pub fn runner_settings(cfg: &CampaignConfig, args: &Args) -> anyhow::Result<Option<RunnerSettings>> {
    let Some(text) = &cfg.runner else {
        if args.job_timeout.is_some() {
            bail!("--job-timeout goes with --runner");
        }
        return Ok(None);
    };
    let template = Template::parse(text).map_err(anyhow::Error::msg)?;
    let timeout_s = args.job_timeout.unwrap_or(DEFAULT_JOB_TIMEOUT_S);
    if !(timeout_s.is_finite() && timeout_s > 0.0) {
        bail!("--job-timeout must be a positive number of seconds");
    }
    Ok(Some(RunnerSettings {
        template,
        timeout: std::time::Duration::from_secs_f64(timeout_s),
        judge: cfg.judge,
        spelling: if cfg.old_spelling {
            ModelSpelling::Old
        } else {
            ModelSpelling::New
        },
        campaign_folder: PathBuf::new(),
    }))
}
