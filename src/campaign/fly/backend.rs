//! The vehicles a campaign's settings name: embedded mocks, PX4 SITL instances it starts itself, runner jobs,
//! or one per MAVLink URL, as many at once as the settings say for that backend.

use std::path::PathBuf;
use std::time::Duration;

use tokio::runtime::Handle;

use crate::bridge::sitl::Px4Build;
use crate::campaign::fly::hitl::{HitlSettings, HitlVehicle};
use crate::campaign::fly::mock_mavlink::{LinkVehicle, MockVehicle};
use crate::campaign::fly::px4::{Px4Settings, Px4Vehicle, default_instances, instance_slots};
use crate::campaign::fly::runner::{RunnerSettings, RunnerVehicle, Template};
use crate::campaign::fly::vehicle::Vehicle;
use crate::campaign::ground::error::CampaignError;
use crate::campaign::screen::parallel::available_threads;
use crate::campaign::settings::mock_profile::MockProfile;
use crate::campaign::settings::{Backend, FleetSettings};

fn config(message: impl Into<String>) -> CampaignError {
    CampaignError::Config(message.into())
}

/// The runner's settings, checked (its template, the cancel command, the job time limit); jobs are prepared
/// in `campaign_folder`.
pub fn runner_settings(s: &FleetSettings, campaign_folder: PathBuf) -> Result<Option<RunnerSettings>, CampaignError> {
    let Backend::Runner(text) = s.backend() else {
        return Ok(None);
    };
    let template = Template::parse(text).map_err(config)?;
    let cancel = s
        .vehicles
        .runner_cancel
        .as_deref()
        .map(Template::parse_cancel)
        .transpose();
    Ok(Some(RunnerSettings {
        template,
        timeout: Duration::from_secs_f64(s.vehicles.job_timeout_s),
        judge: s.judge,
        spelling: s.spelling,
        campaign_folder,
        cancel: cancel.map_err(config)?,
    }))
}

/// The PX4 build a `--px4` campaign flies, checked: a build of a release prgenuav checked, that can fly the
/// campaign's mode with its simulator, with the instances asked for.
pub fn px4_build(s: &FleetSettings) -> Result<Option<Px4Build>, CampaignError> {
    let Backend::Px4(folder) = s.backend() else {
        return Ok(None);
    };
    let build = Px4Build::open(folder).map_err(|e| config(e.to_string()))?;
    build.check_mode(s.mode).map_err(|e| config(e.to_string()))?;
    build.check_bench(s.vehicles.bench).map_err(|e| config(e.to_string()))?;
    build.check_sim(s.vehicles.sim).map_err(|e| config(e.to_string()))?;
    if let Some(k) = s.vehicles.instances.or(s.vehicles.jobs) {
        instance_slots(k).map_err(config)?;
    }
    Ok(Some(build))
}

/// The vehicles that fly `s`: runner jobs prepared in `folder`, PX4 instance slots, embedded mocks, or one per
/// MAVLink URL (each waiting `flight.connect_timeout_s` for its first heartbeat).
pub fn fleet(s: &FleetSettings, folder: PathBuf, handle: &Handle) -> Result<Vec<Box<dyn Vehicle>>, CampaignError> {
    let mode = s.mode;
    match s.backend() {
        Backend::Runner(_) => {
            let runner = runner_settings(s, folder)?.ok_or_else(|| config("no runner template"))?;
            RunnerVehicle::fleet(runner, s.vehicles.jobs.unwrap_or(1)).map_err(config)
        }
        Backend::Px4(_) => {
            let build = px4_build(s)?.ok_or_else(|| config("no PX4 build"))?;
            let speed_factor = s.vehicles.speed_factor;
            let settings = Px4Settings {
                keep_ulog: s.vehicles.keep_ulog,
                mode,
                judge: s.judge,
                anchor: s.flight.anchor_at_vehicle_home,
                timeout_s: s.flight.timeout_s,
                sim: s.vehicles.sim,
                sim_link: s.vehicles.sim_link,
                bench: s.vehicles.bench,
                seed: s.seed,
                ..Px4Settings::new(build, speed_factor)
            };
            let k = (s.vehicles.instances.or(s.vehicles.jobs))
                .unwrap_or_else(|| default_instances(available_threads(), speed_factor));
            let fleet = Px4Vehicle::fleet(handle, &settings, k).map_err(config)?;
            Ok(fleet.into_iter().map(|v| Box::new(v) as Box<dyn Vehicle>).collect())
        }
        Backend::Mock => mocks(s, handle),
        Backend::Hitl(urls) => {
            let settings = HitlSettings {
                mode,
                judge: s.judge,
                timeout_s: s.flight.timeout_s,
                seed: s.seed,
            };
            urls.iter()
                .map(|url| HitlVehicle::new(handle.clone(), url, settings).map(|v| Box::new(v) as Box<dyn Vehicle>))
                .collect::<Result<_, _>>()
                .map_err(config)
        }
        Backend::Links(urls) => Ok(urls
            .iter()
            .map(|url| {
                let v = LinkVehicle::new(
                    handle.clone(),
                    url,
                    mode,
                    s.flight.connect_timeout_s,
                    s.flight.connect_time_scale,
                    s.flight.timeout_s,
                );
                Box::new(v.judged(s.judge, s.flight.anchor_at_vehicle_home)) as Box<dyn Vehicle>
            })
            .collect()),
    }
}

/// The embedded mock autopilots flying `s`'s settings.
fn mocks(s: &FleetSettings, handle: &Handle) -> Result<Vec<Box<dyn Vehicle>>, CampaignError> {
    let m = &s.mock;
    let lockstep = m.lockstep.then(|| Duration::from_secs_f64(m.latency_ms / 1000.0));
    let mut profile = MockProfile::of(m.profile);
    // The gusts the campaign began with: a campaign begun before the mock had them resumes without.
    profile.tuning.gust_acc_m_s2 = m.gust_acc_m_s2;
    Ok((0..m.vehicles)
        .map(|i| {
            Box::new(
                MockVehicle::new(handle.clone(), i, m.speed, s.mode, lockstep)
                    .judged(s.judge, s.flight.anchor_at_vehicle_home)
                    .with_timeout(s.flight.timeout_s)
                    .with_profile(profile.clone())
                    .seeded(s.seed),
            ) as Box<dyn Vehicle>
        })
        .collect())
}
