//! A resumed campaign's settings: the stored `campaign.json`, compared with what the command line and TOML ask
//! now by the library ([`prgenuav::campaign::setup::resume`]); what runs is shown.

use std::path::{Path, PathBuf};

use anyhow::bail;
use prgenuav::campaign::config::Px4Backend;
use prgenuav::campaign::run::CampaignConfig;
use prgenuav::campaign::settings::Requested;
use prgenuav::campaign::setup::resume::{check_resume, load_stored};

use super::Args;

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
    let stored = load_stored(folder)?;
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
    check_resume(&stored, &wanted, &request.req.given, &path)?;
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
