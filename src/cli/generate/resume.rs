//! A resumed campaign's settings: the stored `campaign.json`, compared with what the command line and TOML ask
//! now; a flag that would change a stored setting is refused by name, and what runs is shown.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use prgenuav::campaign::config::Px4Backend;
use prgenuav::campaign::run::CampaignConfig;
use prgenuav::campaign::settings::{Given, Requested};
use prgenuav::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};
use serde_json::Value;

use super::Args;
use crate::cli::values::{Spelling, name_of};

/// What the command line and the TOML file ask for, and whether `--out` was given.
pub(super) struct Request {
    pub(super) req: Requested,
    pub(super) out_given: bool,
}

/// A resumed campaign: its stored settings, once every setting asked for agrees with them.
pub(super) fn resumed(
    folder: &Path,
    args: &Args,
    request: &Request,
    build: &dyn Fn(PathBuf, usize) -> CampaignConfig,
) -> anyhow::Result<CampaignConfig> {
    if request.out_given {
        bail!(
            "--out: a resumed campaign writes into {} (its own folder); drop --out",
            folder.display()
        );
    }
    let path = folder.join("campaign.json");
    let bytes = read_capped_no_follow(&path, MAX_READ_BYTES)?;
    let stored: CampaignConfig =
        serde_json::from_slice(&bytes).with_context(|| format!("{}: not a campaign file", path.display()))?;
    let case = match &args.case {
        // The same file under another spelling (`./missions/m.yaml`, an absolute path) is no conflict.
        Some(c) if same_file(c, &stored.case) => stored.case.clone(),
        Some(c) => c.clone(),
        None => stored.case.clone(),
    };
    let mut wanted = build(case, args.budget.unwrap_or(stored.budget));
    if let (Some(p), Some(s)) = (&wanted.prior, &stored.prior)
        && same_file(p, s)
    {
        wanted.prior = stored.prior.clone();
    }
    // Without --px4, a --speed-factor or --keep-ulog is compared with the stored instances' settings.
    if let (None, Some(p)) = (&wanted.px4, &stored.px4) {
        let f = &args.px4;
        wanted.px4 = Some(Px4Backend {
            speed_factor: f.speed_factor.unwrap_or(p.speed_factor),
            keep_ulog: f.keep_ulog || p.keep_ulog,
            build: p.build.clone(),
        });
    }
    let conflicts = conflicts(&stored, &wanted, &request.req.given, &path)?;
    if !conflicts.is_empty() {
        bail!("{}", conflicts.join("\n"));
    }
    // What runs is what the file says now, whoever wrote it last: when that is not what the campaign began
    // with, shown, even with --quiet.
    if let Some(changed) = super::stored_changes::changes_since_first_run(folder, &stored) {
        eprintln!("{changed}\n{}", stored_summary(&stored, &path));
    }
    Ok(stored)
}

/// The stored settings that decide what runs and where: the case, the budget, the seed, the vehicles.
fn stored_summary(cfg: &CampaignConfig, path: &Path) -> String {
    let vehicles = match (&cfg.runner, &cfg.px4) {
        (Some(t), _) => format!("runner `{t}`"),
        (None, Some(p)) => format!("PX4 build {}", p.build.display()),
        (None, None) => cfg.hfs.join(","),
    };
    format!(
        "resuming as {} says: case {}, budget {}, seed {}, vehicles {vehicles}",
        path.display(),
        cfg.case.display(),
        cfg.budget,
        cfg.seed
    )
}

/// Whether `a` and `b` name one existing file (or, when either cannot be resolved, are spelled alike).
fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// One line per setting asked for that differs from the stored one.
fn conflicts(
    stored: &CampaignConfig,
    wanted: &CampaignConfig,
    given: &[Given],
    path: &Path,
) -> anyhow::Result<Vec<String>> {
    let (stored, wanted) = (serde_json::to_value(stored)?, serde_json::to_value(wanted)?);
    let at = |v: &Value, key: &str| key.split('.').try_fold(v.clone(), |v, k| v.get(k).cloned());
    let mut lines = Vec::new();
    for g in given {
        let (s, w) = (at(&stored, &g.key), at(&wanted, &g.key));
        if s == w {
            continue;
        }
        let value = w.as_ref().map_or("(none)".into(), |w| asked(&g.key, w));
        let asked = match (&g.file, g.switch) {
            (Some(file), _) => format!("{} = {value} in {file}", g.name),
            (None, true) => g.name.clone(),
            (None, false) => format!("{} {value}", g.name),
        };
        lines.push(format!(
            "{asked} conflicts with {} {} stored in {}; drop it or start a new campaign",
            g.key,
            s.as_ref().map_or("(none)".into(), show),
            path.display()
        ));
    }
    Ok(lines)
}

/// The value asked for, as it was typed: campaign.json stores the spelling as `old_spelling`.
fn asked(key: &str, v: &Value) -> String {
    match (key, v) {
        ("old_spelling", Value::Bool(old)) => name_of(if *old { &Spelling::Old } else { &Spelling::New }),
        _ => show(v),
    }
}

/// A stored value as a user would type it: strings bare, lists comma-separated, ranges `MIN,MAX`.
pub(super) fn show(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "(none)".into(),
        Value::Array(a) => a.iter().map(show).collect::<Vec<_>>().join(","),
        Value::Object(o) if o.len() == 2 && o.contains_key("min") && o.contains_key("max") => {
            format!("{},{}", show(&o["min"]), show(&o["max"]))
        }
        other => other.to_string(),
    }
}
