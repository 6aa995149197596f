//! The campaign TOML (`generate --config FILE`, `sample --config FILE`): the expert knobs of a campaign, one
//! section per stage, so `generate --help` stays short while every knob stays reachable and can be kept with
//! the campaign it was run with. A key the file does not know is an error naming the file and the key: a
//! misspelt knob must not silently fall back to its default.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::generator::GeneratorConfig;
use crate::model::Range;
use crate::model::safe_files::{MAX_READ_BYTES, read_capped};

pub use super::keys::Output;
pub use super::keys_run::{Flight, Learning, Mock, Screening};

/// The file's sections; every key is optional (a key left out keeps its default, or the flag's value).
#[derive(Debug, Default, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignToml {
    /// The obstacle construction (the keys of the generator's own configuration).
    #[serde(default)]
    pub generator: Option<GeneratorConfig>,
    #[serde(default)]
    /// `[output]`.
    pub output: Output,
    #[serde(default)]
    /// `[screening]`.
    pub screening: Screening,
    #[serde(default)]
    /// `[mock]`.
    pub mock: Mock,
    #[serde(default)]
    /// `[flight]`.
    pub flight: Flight,
    #[serde(default)]
    /// `[learning]`.
    pub learning: Learning,
}

/// The sections a campaign TOML may have.
pub const SECTIONS: [&str; 6] = ["generator", "output", "screening", "mock", "flight", "learning"];

/// A campaign TOML as read: its sections as written (a generator-only file under `generator`) and as typed.
#[derive(Debug, Default, Clone)]
pub struct Loaded {
    /// The file (`None`: no file).
    pub path: Option<PathBuf>,
    /// Its sections as written.
    pub raw: toml::Table,
    /// Its sections as typed.
    pub toml: CampaignToml,
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
    /// `[generator]`, so a generator-only file works wherever a campaign file does.
    pub fn parse(text: &str, path: &Path) -> Result<Self, String> {
        let raw: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
        let generator_only = !raw.is_empty() && raw.keys().all(|k| !SECTIONS.contains(&k.as_str()));
        let raw = if generator_only {
            GeneratorConfig::from_toml(text)?;
            toml::Table::from_iter([("generator".to_string(), toml::Value::Table(raw))])
        } else {
            raw
        };
        let toml = typed(&raw)?;
        Ok(Self {
            path: Some(path.to_path_buf()),
            raw,
            toml,
        })
    }

    /// The file's name as given, to say where a setting came from.
    pub fn name(&self) -> String {
        self.path
            .as_deref()
            .map_or_else(String::new, |p| p.display().to_string())
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

/// The sections as typed, the generator's checked.
pub fn typed(raw: &toml::Table) -> Result<CampaignToml, String> {
    let c: CampaignToml = toml::Value::Table(raw.clone())
        .try_into()
        .map_err(|e: toml::de::Error| e.to_string())?;
    if let Some(g) = &c.generator {
        g.validate().map_err(|e| format!("[generator] {e}"))?;
    }
    Ok(c)
}

/// Every declared key as a TOML file, each set to its example value (its default where that is a constant).
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

/// `--diagonal 6,11` and the like: a range as `MIN,MAX`.
pub fn parse_range(s: &str) -> Result<Range, String> {
    let (a, b) = s.split_once(',').ok_or_else(|| format!("{s:?}: expected MIN,MAX"))?;
    let num = |t: &str| t.trim().parse::<f64>().map_err(|_| format!("{t:?} is not a number"));
    Ok(Range::new(num(a)?, num(b)?))
}
