//! A resumed campaign's settings: what its `campaign.json` holds, with what is asked now laid over it by each
//! setting's [`Resume`] rule. A fixed setting asked for with another value is refused by name, whoever calls
//! the library, so a resume never flies another campaign under an old folder's name; and a resume names what
//! was changed in `campaign.json` since the first run wrote it (`campaign.first.json`).

use std::path::Path;

use serde_json::Value;

use super::check::at;
use super::request::{Given, Request};
use super::stored::CampaignSettings;
use super::{Loaded, Resume, Setting, all};
use crate::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};

/// `campaign.json` as the campaign's first run wrote it, never rewritten.
pub const FIRST_SETTINGS_FILE: &str = "campaign.first.json";

/// The settings a resume of the campaign in `folder` runs with, as `request` asks: the stored ones, the
/// settings a resume takes again as asked (or inherits) laid over them.
pub fn resumed(folder: &Path, request: &Request) -> Result<CampaignSettings, String> {
    let path = folder.join("campaign.json");
    let stored = CampaignSettings::load(folder).map_err(|e| e.to_string())?;
    let stored_json = serde_json::to_value(&stored).map_err(|e| e.to_string())?;
    let merged = relaid(&stored_json, request, |_| true)?;
    let settings = CampaignSettings::resolve(&merged)?;
    let wanted = serde_json::to_value(&settings).map_err(|e| e.to_string())?;
    refuse_conflicts(&stored_json, &wanted, request, &path)?;
    Ok(settings)
}

/// `request` laid over settings stored as `stored` (JSON by section, the settings `keep` says it holds):
/// every fixed or inherited setting as stored unless asked now, the others as asked now or by default.
pub fn relaid(stored: &Value, request: &Request, keep: fn(&Setting) -> bool) -> Result<Request, String> {
    let mut flags: Vec<(&'static Setting, toml::Value)> = Vec::new();
    for s in all().filter(|s| keep(s) && s.resume != Resume::Asked) {
        if let Some(v) = at(stored, &s.toml_key()).filter(|v| !v.is_null()) {
            flags.push((
                s,
                toml::Value::try_from(v).map_err(|e| format!("{}: {e}", s.toml_key()))?,
            ));
        }
    }
    for g in request.given.iter().filter(|g| !same_path(g, stored, request)) {
        let s = g.setting;
        flags.retain(|(f, _)| f.toml_key() != s.toml_key());
        if let Some(v) = asked_value(request, s) {
            flags.push((s, v));
        }
    }
    Request::new(&Loaded::default(), &flags)
}

/// Refuses every fixed setting `request` gives whose resolved value in `wanted` differs from `stored` (both
/// JSON by section), one line each, naming how it was asked and the stored value in `path`.
pub fn refuse_conflicts(stored: &Value, wanted: &Value, request: &Request, path: &Path) -> Result<(), String> {
    let lines: Vec<String> = (request.given.iter())
        .filter(|g| g.setting.resume == Resume::Fixed && !same_path(g, stored, request))
        .filter_map(|g| conflict(g, stored, wanted, path))
        .collect();
    if lines.is_empty() {
        Ok(())
    } else {
        Err(lines.join("\n"))
    }
}

/// The TOML value `request` asks for `s`.
fn asked_value(request: &Request, s: &Setting) -> Option<toml::Value> {
    let asked = toml::Value::try_from(&request.asked).ok()?;
    asked.get(s.section)?.get(s.key).cloned()
}

/// The line refusing `g` when the value it asks for differs from the stored one.
fn conflict(g: &Given, stored: &Value, wanted: &Value, path: &Path) -> Option<String> {
    let key = g.setting.toml_key();
    let (s, w) = (at(stored, &key), at(wanted, &key));
    if s == w {
        return None;
    }
    Some(format!(
        "{} conflicts with {} {} stored in {}; drop it or start a new campaign",
        g.asked(&w.map_or("(none)".into(), show)),
        g.setting.key,
        s.map_or("(none)".into(), show),
        path.display()
    ))
}

/// Whether `g` names a path setting whose file is the stored one under another spelling (`./missions/m.yaml`,
/// an absolute path): no conflict.
fn same_path(g: &Given, stored: &Value, request: &Request) -> bool {
    let key = g.setting.toml_key();
    if !matches!(key.as_str(), "campaign.case" | "campaign.prior" | "vehicles.px4") {
        return false;
    }
    let (Some(asked), Some(kept)) = (asked_value(request, g.setting), at(stored, &key)) else {
        return false;
    };
    match (asked.as_str(), kept.as_str()) {
        (Some(a), Some(b)) => match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
            (Ok(a), Ok(b)) => a == b,
            _ => a == b,
        },
        _ => false,
    }
}

/// A stored value as a user would type it: strings bare, lists comma-separated, ranges `MIN,MAX`.
pub fn show(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "(none)".into(),
        Value::Array(a) => a.iter().map(show).collect::<Vec<_>>().join(","),
        Value::Object(o) if is_range(v) => format!("{},{}", show(&o["min"]), show(&o["max"])),
        other => other.to_string(),
    }
}

fn is_range(v: &Value) -> bool {
    v.as_object()
        .is_some_and(|o| o.len() == 2 && o.contains_key("min") && o.contains_key("max"))
}

/// Differences named in full; beyond them, a count.
const SHOWN: usize = 12;

/// What to tell about `stored` (campaign.json in `folder` now): `None` when its fixed settings are what the
/// first run wrote, else the changes (or why they cannot be told). A file edited by hand, or by someone else,
/// must not run a changed template, case or budget unseen.
pub fn changes_since_first_run(folder: &Path, stored: &CampaignSettings) -> Option<String> {
    let path = folder.join(FIRST_SETTINGS_FILE);
    let first = read_capped_no_follow(&path, MAX_READ_BYTES)
        .map_err(|e| e.to_string())
        .and_then(|b| serde_json::from_slice::<Value>(&b).map_err(|e| format!("{}: {e}", path.display())))
        .and_then(CampaignSettings::from_json);
    let first = match first {
        Ok(f) => f,
        Err(why) => {
            return Some(format!(
                "cannot tell whether campaign.json changed since the first run ({why})"
            ));
        }
    };
    let (Ok(first), Ok(now)) = (serde_json::to_value(&first), serde_json::to_value(stored)) else {
        return Some("cannot tell whether campaign.json changed since the first run".into());
    };
    let mut lines: Vec<String> = (all().filter(|s| s.resume == Resume::Fixed))
        .filter_map(|s| {
            let key = s.toml_key();
            let (a, b) = (
                at(&first, &key).unwrap_or(&Value::Null),
                at(&now, &key).unwrap_or(&Value::Null),
            );
            (a != b).then(|| format!("{key} {} -> {}", quoted(a), quoted(b)))
        })
        .collect();
    if lines.is_empty() {
        return None;
    }
    let more = lines.len().saturating_sub(SHOWN);
    lines.truncate(SHOWN);
    let mut text = format!(
        "campaign.json differs from what the campaign's first run wrote ({FIRST_SETTINGS_FILE}): {}",
        lines.join("; ")
    );
    if more > 0 {
        text.push_str(&format!("; and {more} more"));
    }
    Some(text)
}

/// A value as typed, in backquotes when it holds spaces (a runner template).
fn quoted(v: &Value) -> String {
    let s = show(v);
    if s.contains(' ') { format!("`{s}`") } else { s }
}

#[cfg(test)]
#[path = "resume_tests.rs"]
mod tests;
