//! A mock setting given on the command line or in the environment: `profile:NAME` and/or `KEY=VALUE,...`.

use anyhow::Context;
use prgenuav::campaign::settings::mock_profile::MockProfile;

/// `profile:NAME` picks the base profile (default `px4-sitl`), every other `KEY=VALUE` overrides a value.
pub fn parse_setting(s: &str) -> anyhow::Result<MockProfile> {
    let mut profile = MockProfile::by_name("px4-sitl").context("no px4-sitl profile")?;
    let mut overrides = Vec::new();
    for kv in s.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if let Some(name) = kv.strip_prefix("profile:") {
            profile = MockProfile::by_name(name).with_context(|| format!("no profile {name:?}"))?;
        } else {
            let (k, v) = kv.split_once('=').with_context(|| format!("{kv:?} is not KEY=VALUE"))?;
            overrides.push((k.trim().to_string(), v.trim().parse::<f64>()?));
        }
    }
    for (k, v) in overrides {
        profile.set(&k, v).map_err(|e| anyhow::anyhow!(e))?;
    }
    Ok(profile)
}
