//! From the command line and the campaign TOML to the campaign's settings: a new campaign's, or a resumed
//! campaign's stored ones once no flag asks for a different value. A resumed campaign must fly as it started
//! (its journal, learnt state and report assume it), so a flag that would change a stored setting is refused
//! by name rather than silently ignored.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::ArgMatches;
use clap::parser::ValueSource;
use prgenuav::campaign::fly::runner::RunnerSettings;
use prgenuav::campaign::run::CampaignConfig;
use prgenuav::campaign::settings::{Given, Loaded, Requested, check_unstored, find, lay_over};
use prgenuav::campaign::setup::fleet::{AtOnce, split};
use prgenuav::campaign::setup::{self, Ask};

use super::GenerateArgs;
use super::resume::Request;
use crate::cli::values::name_of;

/// The campaign to run.
pub struct Plan {
    pub cfg: CampaignConfig,
    pub folder: PathBuf,
    /// Flights at once, per backend (not stored but the runner's jobs: a resumed campaign may change them).
    pub at_once: AtOnce,
    /// Seconds to wait for each MAVLink vehicle's first heartbeat (not stored either).
    pub connect_timeout_s: f64,
    /// With `--runner`: what its jobs share (the template is stored, the time limit not).
    pub runner: Option<RunnerSettings>,
}

/// Reads the TOML file and lays the flags over it; `--resume` then compares, a new campaign builds.
pub fn plan(args: &GenerateArgs, matches: &ArgMatches) -> anyhow::Result<Plan> {
    let file = Loaded::read(args.config.as_deref()).map_err(anyhow::Error::msg)?;
    let request = request(args, matches, &file)?;
    let req = &request.req;
    check_unstored(&req.settings).map_err(anyhow::Error::msg)?;
    args.px4.check_instances()?;
    let mut cfg = match &args.resume {
        Some(folder) => super::resume::resumed(folder, args, &request, &|case, budget| build(case, budget, args, req))?,
        None => fresh(args, req)?,
    };
    // A resumed campaign runs as many jobs as it began with, unless told otherwise.
    cfg.jobs = args.jobs.or(cfg.jobs);
    setup::check(&cfg)?;
    args.px4.check(&cfg)?;
    let s = &req.settings;
    let connect_timeout_s = s.flight.connect_timeout_s();
    let mut runner = super::runner::runner_settings(&cfg, args)?;
    let at_once = split(&cfg, cfg.jobs, s.mock.vehicles, args.px4.instances)?;
    if let (Some(n), None) = (at_once.mock_vehicles, s.mock.vehicles) {
        // `--jobs` on the embedded mocks has the range of `mock.vehicles`.
        if let Some(limit) = find("mock", "vehicles").and_then(|s| s.range) {
            limit
                .check("--jobs on the embedded mocks", n as f64)
                .map_err(anyhow::Error::msg)?;
        }
    }
    // Last, once every setting is known good: a new campaign claims a folder of its own.
    let folder = match &args.resume {
        Some(folder) => folder.clone(),
        None => prgenuav::campaign::store::folder::create_new(&args.out, std::time::SystemTime::now())?,
    };
    if let Some(r) = &mut runner {
        r.campaign_folder = folder.clone();
    }
    Ok(Plan {
        cfg,
        folder,
        at_once,
        connect_timeout_s,
        runner,
    })
}

fn given(m: &ArgMatches, id: &str) -> bool {
    m.value_source(id) == Some(ValueSource::CommandLine)
}

/// The settings asked for: the flags laid over the file, and which stored settings the command line gave.
fn request(args: &GenerateArgs, m: &ArgMatches, file: &Loaded) -> anyhow::Result<Request> {
    let mut req = lay_over(file, &args.settings.given).map_err(anyhow::Error::msg)?;
    let switches = ["keep_ulog"];
    for (id, flag, key) in [
        ("case", "CASE", "case"),
        ("budget", "BUDGET", "budget"),
        ("seed", "--seed", "seed"),
        ("connect", "--connect", "hfs"),
        ("mode", "--mode", "mode"),
        ("judge", "--judge", "judge"),
        ("prior", "--prior", "prior"),
        ("runner", "--runner", "runner"),
        ("px4", "--px4", "px4.build"),
        ("speed_factor", "--speed-factor", "px4.speed_factor"),
        ("keep_ulog", "--keep-ulog", "px4.keep_ulog"),
    ] {
        if given(m, id) {
            req.given.push(Given::flag(flag, switches.contains(&id), key));
        }
    }
    Ok(Request {
        req,
        out_given: given(m, "out"),
    })
}

/// The campaign's settings: what was asked for, the library's defaults for the rest.
pub(super) fn build(case: PathBuf, budget: usize, args: &GenerateArgs, req: &Requested) -> CampaignConfig {
    let ask = Ask {
        case,
        budget,
        seed: args.seed,
        connect: args
            .connect
            .split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect(),
        mode: name_of(&args.mode),
        judge: args.judge.into(),
        prior: args.prior.clone(),
        runner: args.runner.clone(),
        jobs: args.jobs,
        px4: args.px4.backend(),
    };
    setup::build(&ask, req)
}

/// A new campaign: CASE and BUDGET required, every setting checked before anything is sampled or flown.
fn fresh(args: &GenerateArgs, req: &Requested) -> anyhow::Result<CampaignConfig> {
    let (Some(case), Some(budget)) = (args.case.clone(), args.budget) else {
        bail!("give CASE.yaml and BUDGET, or --resume FOLDER");
    };
    let mut cfg = build(absolute(&case)?, budget, args, req);
    // Stored absolute, so `--resume` works from any working folder.
    cfg.prior = cfg.prior.as_deref().map(absolute).transpose()?;
    setup::check_new(&cfg)?;
    Ok(cfg)
}

/// `path` made absolute against the working folder (not resolved through links: the user's spelling stays).
pub(super) fn absolute(path: &Path) -> anyhow::Result<PathBuf> {
    std::path::absolute(path).with_context(|| format!("{}: cannot make the path absolute", path.display()))
}

#[cfg(test)]
#[path = "plan_tests.rs"]
mod tests;
