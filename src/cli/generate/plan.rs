//! From the command line and the campaign TOML to the campaign's settings, by the library's rules: a new
//! campaign's, or a resumed campaign's stored ones once no flag asks for a different value
//! ([`prgenuav::campaign::settings::resume`]); what runs is shown when campaign.json was changed by hand.

use std::path::PathBuf;

use anyhow::bail;
use clap::ArgMatches;
use clap::parser::ValueSource;
use prgenuav::campaign::run::{CampaignSettings, check_new};
use prgenuav::campaign::settings::Choice;
use prgenuav::campaign::settings::resume::{changes_since_first_run, resumed};
use prgenuav::campaign::settings::{Backend, Loaded};

use super::GenerateArgs;

/// The campaign to run.
pub struct Plan {
    pub settings: CampaignSettings,
    pub folder: PathBuf,
}

/// Reads the TOML file and lays the flags over it; `--resume` then compares, a new campaign resolves.
pub fn plan(args: &GenerateArgs, matches: &ArgMatches) -> anyhow::Result<Plan> {
    let file = Loaded::read(args.config.as_deref()).map_err(anyhow::Error::msg)?;
    let mut request = args.settings.request(&file)?;
    request.check().map_err(anyhow::Error::msg)?;
    // Stored absolute, so `--resume` works from any working folder.
    request.make_paths_absolute().map_err(anyhow::Error::msg)?;
    let settings = match &args.resume {
        Some(folder) => {
            if matches.value_source("out") == Some(ValueSource::CommandLine) {
                bail!(
                    "--out: a resumed campaign writes into {} (its own folder); drop --out",
                    folder.display()
                );
            }
            let settings = resumed(folder, &request).map_err(anyhow::Error::msg)?;
            // What runs is what the file says now, whoever wrote it last: when that is not what the campaign
            // began with, shown, even with --quiet.
            let stored = CampaignSettings::load(folder)?;
            if let Some(changed) = changes_since_first_run(folder, &stored) {
                eprintln!("{changed}\n{}", stored_summary(&stored, &folder.join("campaign.json")));
            }
            settings
        }
        None => {
            if !request.asked.campaign.is_new() {
                bail!("give CASE.yaml and BUDGET, or --resume FOLDER");
            }
            CampaignSettings::resolve(&request).map_err(anyhow::Error::msg)?
        }
    };
    check_new(&settings)?;
    // Last, once every setting is known good: a new campaign claims a folder of its own.
    let folder = match &args.resume {
        Some(folder) => folder.clone(),
        None => prgenuav::campaign::store::folder::create_new(&args.out, std::time::SystemTime::now())?,
    };
    Ok(Plan { settings, folder })
}

/// The stored settings that decide what runs and where: the case, the budget, the seed, the vehicles.
fn stored_summary(s: &CampaignSettings, path: &std::path::Path) -> String {
    let vehicles = match s.backend() {
        Backend::Runner(t) => format!("runner `{t}`"),
        Backend::Px4(b) => format!("PX4 build {} (--sim {})", b.display(), s.vehicles.sim.name()),
        Backend::Mock => "mock".into(),
        Backend::Links(urls) => urls.join(","),
        Backend::Hitl(urls) => format!("boards {}", urls.join(",")),
    };
    format!(
        "resuming as {} says: case {}, budget {}, seed {}, vehicles {vehicles}",
        path.display(),
        s.campaign.case.display(),
        s.campaign.budget,
        s.campaign.seed
    )
}

#[cfg(test)]
#[path = "plan_tests.rs"]
mod tests;
