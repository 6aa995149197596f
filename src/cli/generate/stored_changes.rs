//! What was changed in a resumed campaign's `campaign.json` since its first run wrote it: the first run keeps a
//! copy (`campaign.first.json`), and a resume names every setting that differs from it. A file edited by hand,
//! or by someone else, must not run a changed template, case or budget unseen.

use std::path::Path;

use prgenuav::campaign::run::{CampaignConfig, FIRST_SETTINGS_FILE};
use prgenuav::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};
use serde_json::Value;

/// Settings a resume may change by flag (`--jobs`): a difference there is the user's own.
const MAY_CHANGE: [&str; 1] = ["jobs"];
/// Differences named in full; beyond them, a count.
const SHOWN: usize = 12;

/// What to tell about `stored` (campaign.json in `folder` now): `None` when it is what the first run wrote,
/// else the changes (or why they cannot be told).
pub fn changes_since_first_run(folder: &Path, stored: &CampaignConfig) -> Option<String> {
    let path = folder.join(FIRST_SETTINGS_FILE);
    let first = match read_capped_no_follow(&path, MAX_READ_BYTES) {
        Ok(bytes) => serde_json::from_slice::<CampaignConfig>(&bytes).map_err(|e| format!("{}: {e}", path.display())),
        Err(e) => Err(e.to_string()),
    };
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
    let mut lines = Vec::new();
    differences("", &first, &now, &mut lines);
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

/// Each setting (dotted key) whose value differs, as `key FIRST -> NOW`, in key order.
fn differences(prefix: &str, first: &Value, now: &Value, out: &mut Vec<String>) {
    if let (Value::Object(a), Value::Object(b)) = (first, now)
        && !is_range(first)
    {
        let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
        keys.sort();
        keys.dedup();
        for k in keys {
            let key = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            if MAY_CHANGE.contains(&key.as_str()) {
                continue;
            }
            let (x, y) = (a.get(k).unwrap_or(&Value::Null), b.get(k).unwrap_or(&Value::Null));
            differences(&key, x, y, out);
        }
        return;
    }
    if first != now {
        out.push(format!("{prefix} {} -> {}", quoted(first), quoted(now)));
    }
}

fn is_range(v: &Value) -> bool {
    v.as_object()
        .is_some_and(|o| o.len() == 2 && o.contains_key("min") && o.contains_key("max"))
}

/// A value as typed: strings bare, lists comma-separated, ranges `MIN,MAX`.
fn show(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "(none)".into(),
        Value::Array(a) => a.iter().map(show).collect::<Vec<_>>().join(","),
        Value::Object(o) if is_range(v) => format!("{},{}", show(&o["min"]), show(&o["max"])),
        other => other.to_string(),
    }
}

/// A value as typed, in backquotes when it holds spaces (a runner template).
fn quoted(v: &Value) -> String {
    let s = show(v);
    if s.contains(' ') { format!("`{s}`") } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn diff(a: Value, b: Value) -> Vec<String> {
        let mut out = Vec::new();
        differences("", &a, &b, &mut out);
        out
    }

    #[test]
    fn every_changed_setting_is_named_with_both_values_and_jobs_is_the_users_own() {
        let first = json!({"budget": 12, "runner": "srun {test}", "jobs": 2,
                           "generator": {"gap_m": {"min": 1.0, "max": 2.0}, "seed": 0}});
        assert!(diff(first.clone(), first.clone()).is_empty());
        let now = json!({"budget": 20, "runner": "sh evil {test}", "jobs": 8,
                         "generator": {"gap_m": {"min": 1.0, "max": 3.0}, "seed": 0}, "px4": null});
        assert_eq!(
            diff(first, now),
            [
                "budget 12 -> 20",
                "generator.gap_m 1.0,2.0 -> 1.0,3.0",
                "runner `srun {test}` -> `sh evil {test}`",
            ]
        );
    }

    #[test]
    fn a_missing_first_copy_is_said_not_passed_over() {
        let dir = tempfile::tempdir().unwrap();
        let cfg: CampaignConfig = serde_json::from_value(json!({
            "case": "/m.yaml", "seed": 0, "budget": 1, "candidates": 1, "threshold_m": 3.0, "max_iou": 0.5,
            "generator": prgenuav::generator::GeneratorConfig::default(), "old_spelling": false, "hfs": ["mock"]
        }))
        .unwrap();
        let said = changes_since_first_run(dir.path(), &cfg).unwrap();
        assert!(
            said.contains("cannot tell") && said.contains(FIRST_SETTINGS_FILE),
            "{said}"
        );
        prgenuav::io::write_json(&dir.path().join(FIRST_SETTINGS_FILE), &cfg, true).unwrap();
        assert_eq!(changes_since_first_run(dir.path(), &cfg), None);
        let changed = CampaignConfig { budget: 7, ..cfg };
        let said = changes_since_first_run(dir.path(), &changed).unwrap();
        assert!(said.ends_with("budget 1 -> 7"), "{said}");
    }
}
