//! The campaign TOML (`generate --config FILE`, `sample --config FILE`): the expert knobs of a campaign, one
//! section per stage, so `generate --help` stays short while every knob stays reachable and can be kept with
//! the campaign it was run with. A key the file does not know is an error naming the file and the key: a
//! misspelt knob must not silently fall back to its default.

use std::path::{Path, PathBuf};

use crate::generator::GeneratorConfig;
use crate::model::safe_files::{MAX_READ_BYTES, read_capped};

/// The sections a campaign TOML may have.
pub const SECTIONS: [&str; 6] = ["generator", "output", "screening", "mock", "flight", "learning"];

/// The sections only the command line sets: what the campaign is and what flies it.
pub const FLAG_SECTIONS: [&str; 2] = ["campaign", "vehicles"];

/// A campaign TOML as read: its sections as written (a generator-only file under `generator`).
#[derive(Debug, Default, Clone)]
pub struct Loaded {
    /// The file (`None`: no file).
    pub path: Option<PathBuf>,
    /// Its sections as written.
    pub raw: toml::Table,
}

impl Loaded {
    /// Reads `path`, or nothing when `None`; errors name the file.
    pub fn read(path: Option<&Path>) -> Result<Self, String> {
        let Some(path) = path else {
            return Ok(Self::default());
        };
        let bytes = read_capped(path, MAX_READ_BYTES).map_err(|e| e.to_string())?;
        let text = String::from_utf8(bytes).map_err(|_| format!("{}: not UTF-8 text", path.display()))?;
        Self::parse(&text, path).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Parses the text of `path`. A file without sections whose keys are all the generator's is read as
    /// `[generator]`, so a generator-only file works wherever a campaign file does. Every value is typed here
    /// once, so a bad one is named before any flag is looked at.
    pub fn parse(text: &str, path: &Path) -> Result<Self, String> {
        let raw: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
        let generator_only = !raw.is_empty() && raw.keys().all(|k| !SECTIONS.contains(&k.as_str()));
        let raw = if generator_only && raw.keys().all(|k| !FLAG_SECTIONS.contains(&k.as_str())) {
            GeneratorConfig::from_toml(text)?;
            toml::Table::from_iter([("generator".to_string(), toml::Value::Table(raw))])
        } else {
            raw
        };
        if let Some(s) = raw.keys().find(|k| FLAG_SECTIONS.contains(&k.as_str())) {
            return Err(format!(
                "[{s}] is given on the command line (its flags), not in the campaign TOML; the file's sections are \
                 {}",
                SECTIONS.join(", ")
            ));
        }
        super::asked::Asked::typed(&raw)?;
        Ok(Self {
            path: Some(path.to_path_buf()),
            raw,
        })
    }

    /// The file's name as given, to say where a setting came from.
    pub fn name(&self) -> String {
        self.path
            .as_deref()
            .map_or_else(String::new, |p| p.display().to_string())
    }

    /// Whether the file sets `section.key`.
    pub fn sets(&self, section: &str, key: &str) -> bool {
        self.raw
            .get(section)
            .and_then(toml::Value::as_table)
            .is_some_and(|t| t.contains_key(key))
    }

    /// The `[generator]` keys the file sets.
    pub fn generator_keys(&self) -> Vec<String> {
        self.raw
            .get("generator")
            .and_then(toml::Value::as_table)
            .map(|t| t.keys().cloned().collect())
            .unwrap_or_default()
    }
}

/// Every key a campaign TOML may set, as a TOML file, each set to its example value (its default where that is
/// a constant).
pub fn example_toml() -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    for section in SECTIONS {
        let _ = writeln!(s, "[{section}]");
        for k in super::all().filter(|k| k.section == section) {
            let _ = writeln!(s, "{} = {}", k.key, k.example());
        }
    }
    s
}
