//! `generate --px4 BUILD [--instances K] [--speed-factor F] [--keep-ulog]`: the campaign starts its own PX4
//! SITL instances, each flight on a fresh one. Checked before anything is screened or started.

use std::path::PathBuf;

use anyhow::bail;
use prgenuav::bridge::FlyMode;
use prgenuav::bridge::sitl::Px4Build;
use prgenuav::campaign::config::Px4Backend;
use prgenuav::campaign::fly::px4::{DEFAULT_SPEED_FACTOR, instance_slots};
use prgenuav::campaign::run::CampaignConfig;
use prgenuav::campaign::settings::keys::flags;

/// The `--px4` flags.
#[derive(Debug, clap::Args)]
pub struct Px4Flags {
    /// Fly on PX4 SITL instances started here, every flight on a fresh SIH instance at the test's home:
    /// BUILD_DIR is your PX4-Autopilot (v1.14 to v1.17) `build/px4_sitl_default` folder (docs/px4.md).
    #[arg(long, value_name = "BUILD_DIR", conflicts_with = "connect")]
    pub px4: Option<PathBuf>,
    /// PX4 instances flying at once (default: what the machine's cores carry at --speed-factor, docs/px4.md);
    /// --jobs says the same.
    #[arg(long, hide = true, value_name = "K")]
    pub instances: Option<usize>,
    /// PX4_SIM_SPEED_FACTOR of the --px4 instances [default: 5] (a flag only, stored in campaign.json).
    #[arg(long, hide = true, value_name = "F")]
    pub speed_factor: Option<f64>,
    /// Copy each --px4 flight's ULog beside its trajectory, flights/candidate_N.ulg (a flag only, stored in
    /// campaign.json).
    #[arg(long, hide = true)]
    pub keep_ulog: bool,
}

impl Px4Flags {
    /// What campaign.json stores of them (the build folder made absolute, so `--resume` works from anywhere).
    pub fn backend(&self) -> Option<Px4Backend> {
        let build = self.px4.as_ref()?;
        Some(Px4Backend {
            build: std::fs::canonicalize(build).unwrap_or_else(|_| build.clone()),
            speed_factor: self.speed_factor.unwrap_or(DEFAULT_SPEED_FACTOR),
            keep_ulog: self.keep_ulog,
        })
    }

    /// `--instances` within its range, checked before anything else.
    pub fn check_instances(&self) -> anyhow::Result<()> {
        if let Some(k) = self.instances {
            flags::INSTANCES
                .check("--instances", k as f64)
                .map_err(anyhow::Error::msg)?;
        }
        Ok(())
    }

    /// The campaign's PX4 settings are sound and its build folder is a build, before anything runs.
    pub fn check(&self, cfg: &CampaignConfig) -> anyhow::Result<()> {
        let Some(px4) = &cfg.px4 else {
            if self.instances.is_some() || self.speed_factor.is_some() || self.keep_ulog {
                bail!("--instances, --speed-factor and --keep-ulog need --px4 BUILD_DIR");
            }
            return Ok(());
        };
        let build = Px4Build::open(&px4.build)?;
        let mode: FlyMode = crate::cli::values::parse_stored::<crate::cli::values::Mode>(&cfg.mode, "mode")?.into();
        build.check_mode(mode)?;
        flags::PX4_SPEED_FACTOR
            .check("--speed-factor", px4.speed_factor)
            .map_err(anyhow::Error::msg)?;
        if let Some(k) = self.instances {
            instance_slots(k).map_err(anyhow::Error::msg)?;
        }
        Ok(())
    }
}
