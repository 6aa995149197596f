//! `campaign.json`: the campaign's settings as JSON with the format number, what `--resume` continues and
//! `evaluate` reads back; a file without a format number is one written before the settings were sectioned,
//! read by [`super::legacy`].

use std::path::Path;

use super::stored::CampaignSettings;
use crate::model::ModelError;
use crate::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};

/// The format of `campaign.json` this version writes. A file without a format is one written before settings
/// were sectioned: [`super::legacy`] reads it. Format 2 lacks the keys formats 3 and 4 added (`format_3_keys`,
/// `format_4_keys`), format 3 those of format 4.
pub const FORMAT: u64 = 4;

/// The `[vehicles]` keys format 3 added, each with what a format-2 campaign flew with before it existed:
/// PX4's own SIH, no link of ours, no board in the loop.
fn format_3_keys() -> [(&'static str, serde_json::Value); 3] {
    [
        ("sim", serde_json::json!("sih")),
        ("sim_link", serde_json::json!("tcp")),
        ("hitl", serde_json::Value::Null),
    ]
}

/// The `[vehicles]` key format 4 added, with what a format-3 campaign flew with before it existed: no bench.
fn format_4_keys() -> [(&'static str, serde_json::Value); 1] {
    [("bench", serde_json::json!("plain"))]
}

/// A format-2 or format-3 file read as format 4: each missing key as the campaign flew without it.
fn from_older(value: &mut serde_json::Value, format: u64) {
    let Some(vehicles) = value.get_mut("vehicles").and_then(|v| v.as_object_mut()) else {
        return;
    };
    let added = format_4_keys().into_iter();
    let keys: Vec<_> = if format < 3 {
        format_3_keys().into_iter().chain(added).collect()
    } else {
        added.collect()
    };
    for (key, before) in keys {
        vehicles.entry(key).or_insert(before);
    }
}

impl CampaignSettings {
    /// Reads `folder/campaign.json` (a link there is refused), of this format or an older one.
    pub fn load(folder: &Path) -> Result<Self, ModelError> {
        let path = folder.join("campaign.json");
        let bytes = read_capped_no_follow(&path, MAX_READ_BYTES)?;
        let syntax = |message: String| ModelError::Syntax {
            path: path.clone(),
            line: None,
            column: None,
            message,
        };
        let value: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|e| syntax(format!("not a campaign file: {e}")))?;
        Self::from_json(value).map_err(|e| syntax(format!("not a campaign file: {e}")))
    }

    /// The settings of a `campaign.json` value: this format's, or an older file's by [`super::legacy`].
    pub fn from_json(mut value: serde_json::Value) -> Result<Self, String> {
        let object = value.as_object_mut().ok_or("not a JSON object")?;
        match object.remove("format") {
            None => super::legacy::upgrade(value),
            Some(f) if f.as_u64() == Some(FORMAT) => serde_json::from_value(value).map_err(|e| e.to_string()),
            Some(f) if let Some(older @ (2 | 3)) = f.as_u64() => {
                from_older(&mut value, older);
                serde_json::from_value(value).map_err(|e| e.to_string())
            }
            Some(f) => Err(format!(
                "format {f}: this prgenuav reads campaign files of format {FORMAT} and older; a newer prgenuav wrote \
                 it"
            )),
        }
    }

    /// The settings as `campaign.json` holds them (with the format number).
    pub fn to_json(&self) -> Result<serde_json::Value, String> {
        let mut v = serde_json::to_value(self).map_err(|e| e.to_string())?;
        if let Some(o) = v.as_object_mut() {
            o.insert("format".into(), FORMAT.into());
        }
        Ok(v)
    }

    /// Writes `path` (whole, or not at all).
    pub fn save(&self, path: &Path) -> Result<(), ModelError> {
        let v = self.to_json().map_err(|message| ModelError::Syntax {
            path: path.to_path_buf(),
            line: None,
            column: None,
            message,
        })?;
        crate::io::write_json(path, &v, true)
    }
}
