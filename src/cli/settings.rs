//! The campaign TOML (`generate --config FILE`, `sample --config FILE`): the expert knobs of a campaign, one
//! section per stage, so `generate --help` stays short while every knob stays reachable and can be kept with
//! the campaign it was run with. A flag given on the command line overrides the file. A key the file does not
//! know is an error naming the file and the key: a misspelt knob must not silently fall back to its default.

use std::path::{Path, PathBuf};

use prgenuav::generator::GeneratorConfig;
use prgenuav::model::Range;
use prgenuav::model::safe_files::{MAX_READ_BYTES, read_capped};
use serde::{Deserialize, Serialize};

use super::values::{Family, Motion, Spelling};

/// The file's sections; every key is optional (a key left out keeps its default, or the flag's value).
#[derive(Debug, Default, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CampaignToml {
    /// The obstacle construction (the keys of the generator's own configuration).
    #[serde(default)]
    pub generator: Option<GeneratorConfig>,
    /// How the tests are written.
    #[serde(default)]
    pub output: Output,
    /// The low-fidelity screening of the candidates.
    #[serde(default)]
    pub screening: Screening,
    /// The embedded mock autopilots (`--connect mock`).
    #[serde(default)]
    pub mock: Mock,
    /// Every flight, on any vehicle.
    #[serde(default)]
    pub flight: Flight,
    /// Learning from the flights as the campaign goes.
    #[serde(default)]
    pub learning: Learning,
}

/// `[output]`.
#[derive(Debug, Default, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    pub spelling: Option<Spelling>,
}

/// `[screening]`.
#[derive(Debug, Default, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Screening {
    pub candidates: Option<usize>,
    pub threshold_m: Option<f64>,
    pub max_iou: Option<f64>,
    pub motion: Option<Motion>,
    pub ensemble: Option<usize>,
    pub screen: Option<bool>,
}

/// `[mock]`.
#[derive(Debug, Default, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Mock {
    pub speed: Option<f64>,
    pub lockstep: Option<bool>,
    pub latency_ms: Option<f64>,
    pub vehicles: Option<usize>,
    pub profile: Option<String>,
}

/// `[flight]`.
#[derive(Debug, Default, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Flight {
    pub timeout_s: Option<f64>,
    pub connect_timeout_s: Option<f64>,
    pub connect_time_scale: Option<f64>,
    pub anchor_at_vehicle_home: Option<bool>,
    pub confirm: Option<usize>,
    pub overlap: Option<bool>,
}

/// `[learning]`.
#[derive(Debug, Default, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Learning {
    pub learn: Option<bool>,
    pub adapt: Option<bool>,
    pub min_diversity: Option<f64>,
    pub child_max_iou: Option<f64>,
}

/// A campaign TOML as read: its values, and which `[generator]` keys it sets (to compare them with a resumed
/// campaign's).
#[derive(Debug, Default, Clone)]
pub struct Loaded {
    pub path: Option<PathBuf>,
    pub toml: CampaignToml,
    pub generator_keys: Vec<String>,
}

/// The sections a campaign TOML may have.
pub const SECTIONS: [&str; 6] = ["generator", "output", "screening", "mock", "flight", "learning"];

impl Loaded {
    /// Reads `path`, or nothing when `None`.
    pub fn read(path: Option<&Path>) -> anyhow::Result<Self> {
        let Some(path) = path else {
            return Ok(Self::default());
        };
        // As every input: a regular file within the cap, never blocking on a FIFO or a device.
        let bytes = read_capped(path, MAX_READ_BYTES)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            anyhow::anyhow!("{}: not UTF-8 text (invalid byte at offset {at})", path.display())
        })?;
        Self::parse(&text, path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
    }

    /// Parses the text of `path`. A file without sections whose keys are all the generator's is read as
    /// `[generator]`, so a generator-only file works wherever a campaign file does.
    pub fn parse(text: &str, path: &Path) -> Result<Self, String> {
        let raw: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
        let generator_only = !raw.is_empty() && raw.keys().all(|k| !SECTIONS.contains(&k.as_str()));
        let (toml, generator_keys) = if generator_only {
            let g = GeneratorConfig::from_toml(text)?;
            let c = CampaignToml {
                generator: Some(g),
                ..CampaignToml::default()
            };
            (c, raw.keys().cloned().collect())
        } else {
            let c: CampaignToml = toml::from_str(text).map_err(|e| e.to_string())?;
            if let Some(g) = &c.generator {
                g.validate().map_err(|e| format!("[generator] {e}"))?;
            }
            let keys = raw.get("generator").and_then(toml::Value::as_table);
            (c, keys.map(|t| t.keys().cloned().collect()).unwrap_or_default())
        };
        Ok(Self {
            path: Some(path.to_path_buf()),
            toml,
            generator_keys,
        })
    }

    /// The file's name as given, to say where a setting came from.
    pub fn name(&self) -> String {
        self.path
            .as_deref()
            .map_or_else(String::new, |p| p.display().to_string())
    }
}

/// Generator flags (`--diagonal` ...), each overriding its `[generator]` key.
#[derive(Debug, Default, Clone, Copy)]
pub struct GeneratorFlags {
    pub diagonal: Option<Range>,
    pub angle: Option<Range>,
    pub gap: Option<Range>,
    pub height: Option<f64>,
    pub family: Option<Family>,
}

impl GeneratorFlags {
    /// The flags given, as (flag, `[generator]` key).
    pub fn given(&self) -> Vec<(&'static str, &'static str)> {
        [
            (self.diagonal.is_some(), "--diagonal", "diagonal_m"),
            (self.angle.is_some(), "--angle", "angle_deg"),
            (self.gap.is_some(), "--gap", "gap_m"),
            (self.height.is_some(), "--height", "height_m"),
            (self.family.is_some(), "--family", "family"),
        ]
        .into_iter()
        .filter(|(given, _, _)| *given)
        .map(|(_, flag, key)| (flag, key))
        .collect()
    }

    /// The generator's configuration: its defaults, then the file's `[generator]`, then these flags.
    pub fn apply(&self, file: &Loaded) -> anyhow::Result<GeneratorConfig> {
        let mut c = file.toml.generator.clone().unwrap_or_default();
        c.diagonal_m = self.diagonal.unwrap_or(c.diagonal_m);
        c.angle_deg = self.angle.unwrap_or(c.angle_deg);
        c.gap_m = self.gap.unwrap_or(c.gap_m);
        c.height_m = self.height.unwrap_or(c.height_m);
        c.family = self.family.map_or(c.family, Into::into);
        c.validate().map_err(|e| anyhow::anyhow!("generator parameters: {e}"))?;
        Ok(c)
    }
}

/// `--diagonal 6,11` and the like: a range as `MIN,MAX`.
pub fn parse_range(s: &str) -> Result<Range, String> {
    let (a, b) = s.split_once(',').ok_or_else(|| format!("{s:?}: expected MIN,MAX"))?;
    let num = |t: &str| t.trim().parse::<f64>().map_err(|_| format!("{t:?} is not a number"));
    Ok(Range::new(num(a)?, num(b)?))
}

#[cfg(test)]
pub use super::setting_keys::{KEYS, example_toml};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_documented_key_parses_and_every_key_is_documented() {
        let text = example_toml();
        let loaded = Loaded::parse(&text, Path::new("example.toml")).unwrap_or_else(|e| panic!("{e}\n{text}"));
        let json = serde_json::to_value(&loaded.toml).unwrap();
        for section in SECTIONS {
            let keys = json[section].as_object().unwrap();
            for (k, v) in keys {
                assert!(!v.is_null(), "[{section}] {k} is not documented in KEYS");
            }
            let documented = KEYS.iter().filter(|k| k.section == section).count();
            assert_eq!(documented, keys.len(), "[{section}]");
        }
        assert_eq!(
            loaded.generator_keys.len(),
            KEYS.iter().filter(|k| k.section == "generator").count()
        );
    }

    #[test]
    fn unknown_keys_and_sections_are_named() {
        let p = Path::new("c.toml");
        let e = Loaded::parse("[screening]\nthreshold = 2\n", p).unwrap_err();
        assert!(e.contains("threshold") && e.contains("threshold_m"), "{e}");
        let e = Loaded::parse("[screenng]\nthreshold_m = 2\n", p).unwrap_err();
        assert!(e.contains("screenng"), "{e}");
        let e = Loaded::parse("[generator]\ngap_m = { min = 5.0, max = 1.0 }\n", p).unwrap_err();
        assert!(e.contains("gap_m"), "{e}");
        let e = Loaded::parse("[mock]\nspeed = \"fast\"\n", p).unwrap_err();
        assert!(e.contains("speed"), "{e}");
    }

    #[test]
    fn a_file_of_generator_keys_alone_is_the_generator_section() {
        let l = Loaded::parse("family = \"extended\"\n", Path::new("g.toml")).unwrap();
        assert_eq!(
            l.toml.generator.map(|g| g.family),
            Some(prgenuav::generator::Family::Extended)
        );
        assert_eq!(l.generator_keys, ["family"]);
        let e = Loaded::parse("gap_m = { min = 2.5, max = 3.0 }\nbogus = 1\n", Path::new("g.toml")).unwrap_err();
        assert!(e.contains("bogus"), "{e}");
    }
}
