//! The layers of a campaign's settings: the defaults, the campaign TOML, then the flags given, each replacing
//! the key below it; and the check of every value against its declared range and choices.

use serde_json::Value;

use super::file::{CampaignToml, Loaded, typed};
use super::{Setting, all};
use crate::generator::GeneratorConfig;

/// A setting given explicitly, by a flag or by the TOML file.
#[derive(Debug, Clone, PartialEq)]
pub struct Given {
    /// `--seed`, or `screening.threshold_m`.
    pub name: String,
    /// The TOML file that gave it (`None`: the command line).
    pub file: Option<String>,
    /// A switch (`--no-learn`) is named without a value.
    pub switch: bool,
    /// Its key in campaign.json (`seed`, `generator.gap_m`).
    pub key: String,
}

impl Given {
    /// A flag of the command line that sets campaign.json's `key`.
    pub fn flag(name: &str, switch: bool, key: &str) -> Self {
        Self {
            name: name.to_string(),
            file: None,
            switch,
            key: key.to_string(),
        }
    }
}

/// What the command line and the TOML file ask for: the flags laid over the file.
#[derive(Debug, Clone, Default)]
pub struct Requested {
    /// The sections, flags laid over the file.
    pub settings: CampaignToml,
    /// The generator's configuration: its defaults under the file's keys and the flags.
    pub generator: GeneratorConfig,
    /// The stored settings given, for a resumed campaign's comparison with what it stored.
    pub given: Vec<Given>,
}

/// Lays the flags given (each with its key's TOML value) over the file: a flag replaces its key. A key is
/// recorded as given when a flag or the file sets it and campaign.json stores it.
pub fn lay_over(file: &Loaded, flags: &[(&'static Setting, toml::Value)]) -> Result<Requested, String> {
    let mut raw = file.raw.clone();
    let mut given = Vec::new();
    for s in all() {
        let flag = flags.iter().find(|(f, _)| f.section == s.section && f.key == s.key);
        let in_file = raw
            .get(s.section)
            .and_then(toml::Value::as_table)
            .is_some_and(|t| t.contains_key(s.key));
        if let (Some((_, v)), Some(f)) = (flag, &s.flag) {
            check_value(s, &serde_json::to_value(v).map_err(|e| e.to_string())?)?;
            let section = raw
                .entry(s.section)
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            let table = section
                .as_table_mut()
                .ok_or_else(|| format!("{}: [{}] is not a section", file.name(), s.section))?;
            table.insert(s.key.to_string(), v.clone());
            if !s.stored.is_empty() {
                given.push(Given::flag(f.long, f.is_switch(), s.stored));
            }
        } else if in_file && !s.stored.is_empty() {
            given.push(Given {
                name: s.toml_key(),
                file: Some(file.name()),
                switch: false,
                key: s.stored.to_string(),
            });
        }
    }
    let settings = typed(&raw).map_err(|e| match &file.path {
        Some(_) => format!("{} (with the flags given): {e}", file.name()),
        None => e,
    })?;
    Ok(Requested {
        generator: settings.generator.clone().unwrap_or_default(),
        settings,
        given,
    })
}

/// The value at a dotted `key` of a JSON object.
pub fn at<'a>(v: &'a Value, key: &str) -> Option<&'a Value> {
    key.split('.').try_fold(v, |v, k| v.get(k))
}

/// Checks `v`, the value of `s`, against its declared range (both ends of a `{min, max}` range) and choices.
pub fn check_value(s: &Setting, v: &Value) -> Result<(), String> {
    if let Some(limit) = &s.range {
        let numbers: Vec<f64> = match v {
            Value::Object(o) => ["min", "max"].iter().filter_map(|k| o.get(*k)?.as_f64()).collect(),
            other => other.as_f64().into_iter().collect(),
        };
        for n in numbers {
            limit.check(&s.names(), n)?;
        }
    }
    if let (false, Some(name)) = (s.choices.is_empty(), v.as_str())
        && !s.choices.iter().any(|(c, _)| *c == name)
    {
        let names: Vec<&str> = s.choices.iter().map(|(c, _)| *c).collect();
        return Err(format!("{} {name:?} is not one of {}", s.names(), names.join(", ")));
    }
    Ok(())
}

/// Checks every stored setting of `stored` (campaign.json's form, a new or a resumed campaign's) against its
/// declaration.
pub fn check_ranges(stored: &Value) -> Result<(), String> {
    for s in all().filter(|s| !s.stored.is_empty()) {
        if let Some(v) = at(stored, s.stored).filter(|v| !v.is_null()) {
            check_value(s, v)?;
        }
    }
    Ok(())
}

/// Checks the settings campaign.json does not store, as asked for.
pub fn check_unstored(settings: &CampaignToml) -> Result<(), String> {
    let v = serde_json::to_value(settings).map_err(|e| e.to_string())?;
    for s in all().filter(|s| s.stored.is_empty()) {
        if let Some(x) = at(&v, &s.toml_key()).filter(|x| !x.is_null()) {
            check_value(s, x)?;
        }
    }
    Ok(())
}
