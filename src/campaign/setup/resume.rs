//! A resumed campaign's settings: the stored `campaign.json`, and the check that nothing asked now would change
//! one of them. A setting asked for that differs from the stored one is refused by name, whoever calls the
//! library, so a resume never flies another campaign under an old folder's name.

use std::path::Path;

use serde_json::Value;

use crate::campaign::config::CampaignConfig;
use crate::campaign::ground::error::CampaignError;
use crate::campaign::settings::Given;
use crate::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};

/// The settings stored in `folder/campaign.json`.
pub fn load_stored(folder: &Path) -> Result<CampaignConfig, CampaignError> {
    let path = folder.join("campaign.json");
    let bytes = read_capped_no_follow(&path, MAX_READ_BYTES)?;
    serde_json::from_slice(&bytes)
        .map_err(|e| CampaignError::Config(format!("{}: not a campaign file: {e}", path.display())))
}

/// Refuses every setting in `given` (what the request set explicitly) whose value in `wanted` differs from
/// `stored`, the settings read from `path`: one line per setting, naming how it was asked and the stored value.
pub fn check_resume(
    stored: &CampaignConfig,
    wanted: &CampaignConfig,
    given: &[Given],
    path: &Path,
) -> Result<(), CampaignError> {
    let as_json = |c: &CampaignConfig| serde_json::to_value(c).map_err(|e| CampaignError::Config(e.to_string()));
    let (stored, wanted) = (as_json(stored)?, as_json(wanted)?);
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
    if lines.is_empty() {
        return Ok(());
    }
    Err(CampaignError::Config(lines.join("\n")))
}

/// The value asked for, as it was typed: campaign.json stores the spelling as `old_spelling`.
fn asked(key: &str, v: &Value) -> String {
    match (key, v) {
        ("old_spelling", Value::Bool(old)) => (if *old { "old" } else { "new" }).to_string(),
        _ => show(v),
    }
}

/// A stored value as a user would type it: strings bare, lists comma-separated, ranges `MIN,MAX`.
pub fn show(v: &Value) -> String {
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn stored() -> CampaignConfig {
        let text = std::fs::read_to_string("tests/data/static-killed/campaign.json").unwrap();
        serde_json::from_str(&text).unwrap()
    }

    #[test]
    fn a_setting_asked_otherwise_is_refused_by_name_and_an_equal_one_is_not() {
        let stored = stored();
        let path = PathBuf::from("f/campaign.json");
        let mut wanted = stored.clone();
        wanted.seed += 1;
        let given = [Given::flag("--seed", false, "seed")];
        let e = check_resume(&stored, &wanted, &given, &path).unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "--seed {} conflicts with seed {}",
                stored.seed + 1,
                stored.seed
            )),
            "{e}"
        );
        assert!(e.contains("f/campaign.json"), "{e}");
        assert!(check_resume(&stored, &stored, &given, &path).is_ok());
        // Only what was asked for is compared.
        assert!(check_resume(&stored, &wanted, &[], &path).is_ok());
    }

    #[test]
    fn the_spelling_is_named_as_typed() {
        let stored = stored();
        let wanted = CampaignConfig {
            old_spelling: !stored.old_spelling,
            ..stored.clone()
        };
        let given = [Given::flag("--spelling", false, "old_spelling")];
        let e = check_resume(&stored, &wanted, &given, Path::new("c.json"))
            .unwrap_err()
            .to_string();
        let typed = if wanted.old_spelling {
            "--spelling old"
        } else {
            "--spelling new"
        };
        assert!(e.starts_with(typed), "{e}");
    }
}
