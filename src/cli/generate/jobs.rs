//! `--jobs N`: one name for the flights flying at once, whichever backend flies them. The backends' own
//! names (`--mock-vehicles`, `mock.vehicles`, `--instances`) stay accepted; they must agree with `--jobs`.

use anyhow::bail;
use prgenuav::campaign::run::CampaignConfig;

/// Flights at once, per backend (`None`: the backend's default).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AtOnce {
    /// Embedded mock autopilots.
    pub mock_vehicles: Option<usize>,
    /// `--runner` jobs.
    pub runner_jobs: Option<usize>,
    /// `--px4` instances.
    pub px4_instances: Option<usize>,
}

/// Gives `jobs` to the backend `cfg` flies on, checking it against that backend's own setting.
pub fn split(
    cfg: &CampaignConfig,
    jobs: Option<usize>,
    mock_vehicles: Option<usize>,
    instances: Option<usize>,
) -> anyhow::Result<AtOnce> {
    if jobs == Some(0) {
        bail!("--jobs 0 is out of range: 1 or more");
    }
    let agree = |own: Option<usize>, name: &str| -> anyhow::Result<Option<usize>> {
        match (jobs, own) {
            (Some(j), Some(o)) if j != o => bail!("--jobs {j} and {name} {o} disagree: give one"),
            _ => Ok(own.or(jobs)),
        }
    };
    let mut at_once = AtOnce {
        mock_vehicles,
        runner_jobs: None,
        px4_instances: instances,
    };
    if cfg.runner.is_some() {
        at_once.runner_jobs = jobs;
    } else if cfg.px4.is_some() {
        at_once.px4_instances = agree(instances, "--instances")?;
    } else if cfg.hfs == ["mock"] {
        at_once.mock_vehicles = agree(mock_vehicles, "--mock-vehicles (mock.vehicles)")?;
    } else if jobs.is_some() {
        bail!("--jobs: with --connect URLs each URL flies one flight at a time; give more URLs for more at once");
    }
    Ok(at_once)
}
