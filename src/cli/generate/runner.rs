//! `generate --runner 'COMMAND' [--jobs N] [--job-timeout S]`: the settings every runner job shares, checked
//! before anything is drawn or flown.

use std::path::PathBuf;

use anyhow::bail;
use prgenuav::campaign::fly::runner::{DEFAULT_JOB_TIMEOUT_S, RunnerSettings, Template};
use prgenuav::campaign::run::CampaignConfig;
use prgenuav::model::Spelling as ModelSpelling;

use super::GenerateArgs;
use prgenuav::campaign::settings::keys::flags::{JOB_TIMEOUT, JOBS};

/// The runner's settings, checked before the campaign claims its folder (`campaign_folder` is set then).
pub fn runner_settings(cfg: &CampaignConfig, args: &GenerateArgs) -> anyhow::Result<Option<RunnerSettings>> {
    let Some(text) = &cfg.runner else {
        if args.job_timeout.is_some() || args.runner_cancel.is_some() {
            bail!("--job-timeout and --runner-cancel go with --runner");
        }
        return Ok(None);
    };
    let template = Template::parse(text).map_err(anyhow::Error::msg)?;
    let cancel = args.runner_cancel.as_deref().map(Template::parse_cancel).transpose();
    if let Some(jobs) = cfg.jobs {
        JOBS.check("--jobs", jobs as f64).map_err(anyhow::Error::msg)?;
    }
    let timeout = JOB_TIMEOUT
        .seconds("--job-timeout", args.job_timeout.unwrap_or(DEFAULT_JOB_TIMEOUT_S))
        .map_err(anyhow::Error::msg)?;
    Ok(Some(RunnerSettings {
        template,
        timeout,
        judge: cfg.judge,
        spelling: if cfg.old_spelling {
            ModelSpelling::Old
        } else {
            ModelSpelling::New
        },
        campaign_folder: PathBuf::new(),
        cancel: cancel.map_err(anyhow::Error::msg)?,
    }))
}
