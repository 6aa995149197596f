//! The vehicles that fly a campaign: embedded mocks, PX4 SITL instances it starts itself, runner jobs, or one
//! per MAVLink URL; and how many fly at once when `--jobs` names the number for whichever backend flies.

use std::time::Duration;

use tokio::runtime::Handle;

use crate::bridge::sitl::Px4Build;
use crate::campaign::config::CampaignConfig;
use crate::campaign::fly::mock_mavlink::{LinkVehicle, MockVehicle};
use crate::campaign::fly::px4::{Px4Settings, Px4Vehicle, default_instances};
use crate::campaign::fly::runner::{RunnerSettings, RunnerVehicle};
use crate::campaign::fly::vehicle::Vehicle;
use crate::campaign::ground::error::CampaignError;
use crate::campaign::screen::parallel::available_threads;
use crate::campaign::settings::mock_profile::MockProfile;

/// Flights at once, per backend (`None`: the backend's default).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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
) -> Result<AtOnce, CampaignError> {
    if jobs == Some(0) {
        return Err(CampaignError::Config("--jobs 0 is out of range: 1 or more".into()));
    }
    let agree = |own: Option<usize>, name: &str| match (jobs, own) {
        (Some(j), Some(o)) if j != o => Err(CampaignError::Config(format!(
            "--jobs {j} and {name} {o} disagree: give one"
        ))),
        _ => Ok(own.or(jobs)),
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
        return Err(CampaignError::Config(
            "--jobs: with --connect URLs each URL flies one flight at a time; give more URLs for more at once".into(),
        ));
    }
    Ok(at_once)
}

/// The vehicles that fly `cfg`: runner jobs (`runner`), PX4 instance slots, embedded mocks, or one per
/// MAVLink URL (each waiting `connect_timeout_s` for its first heartbeat).
pub fn fleet(
    cfg: &CampaignConfig,
    at_once: &AtOnce,
    connect_timeout_s: f64,
    runner: Option<RunnerSettings>,
    handle: &Handle,
) -> Result<Vec<Box<dyn Vehicle>>, CampaignError> {
    if let Some(runner) = runner {
        return RunnerVehicle::fleet(runner, at_once.runner_jobs.unwrap_or(1)).map_err(CampaignError::Config);
    }
    let mode = super::fly_mode(&cfg.mode)?;
    if let Some(px4) = &cfg.px4 {
        let build = Px4Build::open(&px4.build).map_err(|e| CampaignError::Config(e.to_string()))?;
        let settings = Px4Settings {
            keep_ulog: px4.keep_ulog,
            mode,
            judge: cfg.judge,
            anchor: cfg.anchor_at_vehicle_home,
            timeout_s: cfg.flight_timeout_s,
            ..Px4Settings::new(build, px4.speed_factor)
        };
        let k = at_once
            .px4_instances
            .unwrap_or_else(|| default_instances(available_threads(), px4.speed_factor));
        let fleet = Px4Vehicle::fleet(handle, &settings, k).map_err(CampaignError::Config)?;
        return Ok(fleet.into_iter().map(|v| Box::new(v) as Box<dyn Vehicle>).collect());
    }
    if cfg.hfs == ["mock"] {
        return mocks(
            cfg,
            at_once.mock_vehicles.unwrap_or_else(available_threads),
            mode,
            handle,
        );
    }
    Ok(cfg
        .hfs
        .iter()
        .map(|url| {
            let v = LinkVehicle::new(
                handle.clone(),
                url,
                mode,
                connect_timeout_s,
                cfg.hfs_time_scale,
                cfg.flight_timeout_s,
            );
            Box::new(v.judged(cfg.judge, cfg.anchor_at_vehicle_home)) as Box<dyn Vehicle>
        })
        .collect())
}

/// `count` embedded mock autopilots flying `cfg`'s settings.
fn mocks(
    cfg: &CampaignConfig,
    count: usize,
    mode: crate::bridge::FlyMode,
    handle: &Handle,
) -> Result<Vec<Box<dyn Vehicle>>, CampaignError> {
    if count == 0 {
        return Err(CampaignError::Config(
            "--mock-vehicles (mock.vehicles) must be at least 1".into(),
        ));
    }
    let lockstep = cfg
        .mock_lockstep
        .then(|| Duration::from_secs_f64(cfg.mock_latency_ms / 1000.0));
    let mut profile =
        MockProfile::named(&cfg.mock_profile).map_err(|e| CampaignError::Config(format!("mock.profile: {e}")))?;
    // The gusts the campaign began with: a campaign begun before the mock had them resumes without.
    profile.tuning.gust_acc_m_s2 = cfg.mock_gust_acc_m_s2;
    Ok((0..count)
        .map(|i| {
            Box::new(
                MockVehicle::new(handle.clone(), i, cfg.mock_speed, mode, lockstep)
                    .judged(cfg.judge, cfg.anchor_at_vehicle_home)
                    .with_timeout(cfg.flight_timeout_s)
                    .with_profile(profile.clone())
                    .seeded(cfg.seed),
            ) as Box<dyn Vehicle>
        })
        .collect())
}
