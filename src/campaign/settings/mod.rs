//! Every campaign setting declared once: its section and key in the campaign TOML, its command-line flag, its
//! key in `campaign.json`, its default, its range and its doc all come from one [`Setting`] in [`keys`]. The
//! file's section types are generated from the same declaration, the flags are built from it, ranges are
//! checked from it, and docs/cli.md renders it.

pub mod file;
pub mod keys;
mod keys_run;
pub mod mock_profile;

pub mod merge;

pub use crate::model::Limit;
pub use file::{CampaignToml, Flight, Learning, Loaded, Mock, Output, SECTIONS, Screening, example_toml, parse_range};
pub use merge::{Given, Requested, check_ranges, check_unstored, lay_over};

/// One setting of the campaign TOML.
#[derive(Debug, Clone, Copy)]
pub struct Setting {
    /// `[section]` of the campaign TOML.
    pub section: &'static str,
    /// Its key in the section.
    pub key: &'static str,
    /// The `generate` flag that sets it, if any.
    pub flag: Option<Flag>,
    /// Its key in campaign.json (dotted below the top level); empty: not stored, a resumed campaign may change it.
    pub stored: &'static str,
    /// Its default when neither the file nor a flag gives it.
    pub default: DefaultValue,
    /// Its accepted numbers (a range of numbers: each end).
    pub range: Option<Limit>,
    /// Its accepted names and what each means (empty: any value of its type).
    pub choices: &'static [(&'static str, &'static str)],
    /// What it does.
    pub help: &'static str,
    /// Reads the flag's text as the key's TOML value.
    pub parse: fn(&str) -> Result<toml::Value, String>,
}

/// A setting's default.
#[derive(Debug, Clone, Copy)]
pub enum DefaultValue {
    /// A constant, as the TOML value (`None` only if it cannot be written as TOML, which a test rules out).
    Constant(fn() -> Option<toml::Value>),
    /// Decided by the campaign's setup (the budget, the vehicles): said in words, with an example value.
    Setup {
        /// The rule, in words.
        doc: &'static str,
        /// A valid value.
        example: &'static str,
    },
}

/// A setting's command-line flag.
#[derive(Debug, Clone, Copy)]
pub struct Flag {
    /// `--mock-speed`.
    pub long: &'static str,
    /// The value's name in the usage (`K`); empty for a switch.
    pub value_name: &'static str,
    /// The value a switch sets (`--no-learn`: `false`).
    pub sets: bool,
    /// Shown in `--help` (the others are expert flags, listed in docs/cli.md).
    pub shown: bool,
    /// Another spelling still accepted (empty: none).
    pub alias: &'static str,
    /// The flag's own help; empty: the key's, naming the key.
    pub help: &'static str,
    /// An argument id it cannot be given with (empty: none).
    pub conflicts_with: &'static str,
}

impl Flag {
    /// A hidden flag taking a value.
    pub const fn value(long: &'static str, value_name: &'static str) -> Self {
        Self {
            long,
            value_name,
            sets: true,
            shown: false,
            alias: "",
            help: "",
            conflicts_with: "",
        }
    }

    /// A hidden switch setting the key to `sets`.
    pub const fn switch(long: &'static str, sets: bool) -> Self {
        Self {
            value_name: "",
            sets,
            ..Self::value(long, "")
        }
    }

    /// The same flag with its own help.
    pub const fn helped(self, help: &'static str) -> Self {
        Self { help, ..self }
    }

    /// The same flag, shown in `--help` with its own help.
    pub const fn shown(self, help: &'static str) -> Self {
        Self {
            shown: true,
            help,
            ..self
        }
    }

    /// Whether it takes no value.
    pub fn is_switch(&self) -> bool {
        self.value_name.is_empty()
    }

    /// The command-line argument's id: the flag without its dashes (`no-learn`).
    pub fn id(&self) -> &'static str {
        self.long.trim_start_matches('-')
    }
}

impl Setting {
    /// `section.key`.
    pub fn toml_key(&self) -> String {
        format!("{}.{}", self.section, self.key)
    }

    /// How errors name it: `--mock-speed (mock.speed)`, or the key alone when no flag sets it.
    pub fn names(&self) -> String {
        match &self.flag {
            Some(f) => format!("{} ({})", f.long, self.toml_key()),
            None => self.toml_key(),
        }
    }

    /// The default as a TOML value, when it is a constant.
    pub fn default_value(&self) -> Option<toml::Value> {
        match self.default {
            DefaultValue::Constant(f) => f(),
            DefaultValue::Setup { .. } => None,
        }
    }

    /// A valid TOML value for it: the default where it is a constant.
    pub fn example(&self) -> String {
        match self.default {
            DefaultValue::Constant(f) => f().map_or_else(String::new, |v| inline(&v)),
            DefaultValue::Setup { example, .. } => example.to_string(),
        }
    }

    /// The flag's help: its own, or the key's naming the key.
    pub fn flag_help(&self) -> String {
        match &self.flag {
            Some(f) if !f.help.is_empty() => f.help.to_string(),
            Some(f) if f.is_switch() => format!("Sets {} = {}.", self.toml_key(), f.sets),
            _ => format!("{} ({}).", self.help.trim_end_matches('.'), self.toml_key()),
        }
    }
}

/// Every setting, in file order.
pub fn all() -> impl Iterator<Item = &'static Setting> {
    [
        keys::GENERATOR,
        keys::OUTPUT,
        keys_run::SCREENING,
        keys_run::MOCK,
        keys_run::FLIGHT,
        keys_run::LEARNING,
    ]
    .into_iter()
    .flatten()
}

/// The setting `section.key`.
pub fn find(section: &str, key: &str) -> Option<&'static Setting> {
    all().find(|s| s.section == section && s.key == key)
}

/// A TOML value on one line, as a file would spell it (`{ min = 2.0, max = 4.0 }`).
pub fn inline(v: &toml::Value) -> String {
    match v {
        toml::Value::Table(t) if t.len() == 2 && t.contains_key("min") && t.contains_key("max") => {
            format!("{{ min = {}, max = {} }}", t["min"], t["max"])
        }
        toml::Value::Table(t) => {
            let parts: Vec<String> = t.iter().map(|(k, v)| format!("{k} = {}", inline(v))).collect();
            format!("{{ {} }}", parts.join(", "))
        }
        other => other.to_string(),
    }
}

/// A value type a flag can set: how its text becomes the key's TOML value.
pub trait FlagText {
    /// The TOML value of `text`, or why it is none.
    fn parse(text: &str) -> Result<toml::Value, String>;
}

#[cfg(test)]
mod tests;

impl FlagText for f64 {
    fn parse(text: &str) -> Result<toml::Value, String> {
        let v: f64 = text.trim().parse().map_err(|_| format!("{text:?} is not a number"))?;
        Ok(toml::Value::Float(v))
    }
}

impl FlagText for usize {
    fn parse(text: &str) -> Result<toml::Value, String> {
        let v: i64 = text
            .trim()
            .parse()
            .map_err(|_| format!("{text:?} is not a whole number"))?;
        if v < 0 {
            return Err(format!("{text:?} is negative"));
        }
        Ok(toml::Value::Integer(v))
    }
}

impl FlagText for u32 {
    fn parse(text: &str) -> Result<toml::Value, String> {
        <usize as FlagText>::parse(text)
    }
}

impl FlagText for bool {
    fn parse(text: &str) -> Result<toml::Value, String> {
        text.trim()
            .parse()
            .map(toml::Value::Boolean)
            .map_err(|_| format!("{text:?} is not true or false"))
    }
}

impl FlagText for String {
    fn parse(text: &str) -> Result<toml::Value, String> {
        Ok(toml::Value::String(text.to_string()))
    }
}

impl FlagText for crate::model::Range {
    fn parse(text: &str) -> Result<toml::Value, String> {
        let r = parse_range(text)?;
        let mut t = toml::Table::new();
        t.insert("min".into(), toml::Value::Float(r.min));
        t.insert("max".into(), toml::Value::Float(r.max));
        Ok(toml::Value::Table(t))
    }
}

impl FlagText for crate::generator::Family {
    fn parse(text: &str) -> Result<toml::Value, String> {
        Ok(toml::Value::String(text.to_string()))
    }
}
