//! Every setting of a campaign declared once, as ripgrep declares its flags: its section and key, its flag, its
//! type, its one default (a constant, or a rule of the campaign's setup), its range and its doc come from one
//! declaration. From that declaration come the campaign TOML's sections, the
//! command line's flags, the typed settings a campaign runs with and stores as `campaign.json`, the one check
//! of every value, and docs/cli.md. The declarations are in [`keys`] (the command line's own sections),
//! [`keys_draw`] (what is drawn, written and screened) and [`keys_run`] (the flights and learning).
//!
//! A value goes one way: the TOML file and the flags give the *asked* layer ([`request`], every key optional,
//! typed once by serde), [`resolve`] fills in the defaults (the setup's rules included) to give
//! [`CampaignSettings`] ([`stored`]), [`check`] checks it, and the campaign runs it. `campaign.json` is that
//! type as JSON; a file older than it is read by the one rule of [`legacy`].

pub mod asked;
pub mod check;
pub mod choice;
mod declare;
pub mod evaluation;
pub mod file;
pub mod json;
pub mod keys;
pub mod keys_draw;
pub mod keys_run;
pub mod legacy;
pub mod mock_profile;
pub mod request;
pub mod resolve;
pub mod resume;
pub mod rules;
pub mod stored;

pub use crate::model::Limit;
pub use choice::parse_range;
pub use choice::{Choice, SettingValue};
pub use file::{Loaded, SECTIONS, example_toml};
pub use request::{Given, Request};
pub use stored::{Backend, CampaignSettings, FleetSettings};

/// One setting.
#[derive(Debug, Clone, Copy)]
pub struct Setting {
    /// Its section: a `[section]` of the campaign TOML, or a section only the command line sets
    /// ([`file::FLAG_SECTIONS`]).
    pub section: &'static str,
    /// Its key in the section.
    pub key: &'static str,
    /// The command line's flag or positional argument that sets it, if any.
    pub flag: Option<Flag>,
    /// What a resumed campaign does with it (`campaign.json` holds every setting as the run used it).
    pub resume: Resume,
    /// Its default when neither the file nor a flag gives it.
    pub default: DefaultValue,
    /// Its accepted numbers (a range of numbers: each end).
    pub range: Option<Limit>,
    /// Its accepted names and what each means (empty: any value of its type), from its type.
    pub choices: fn() -> &'static [(&'static str, &'static str)],
    /// What it does.
    pub help: &'static str,
    /// Reads the flag's text as the key's TOML value.
    pub parse: fn(&str) -> Result<toml::Value, String>,
}

/// What a resumed campaign does with a setting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resume {
    /// Fixed for the campaign's life: a resume asking for another value is refused by name (the journal,
    /// the learnt state and the report assume it).
    Fixed,
    /// As asked now, else as the campaign last ran (`--jobs`).
    Inherited,
    /// As asked now, else its default: how this run goes, not what the campaign is (`--instances`).
    Asked,
}

/// A setting's default.
#[derive(Debug, Clone, Copy)]
pub enum DefaultValue {
    /// A constant, as the TOML value (`None` only if it cannot be written as TOML, which a test rules out).
    Constant(fn() -> Option<toml::Value>),
    /// A rule of the campaign's setup (the budget, the vehicles, the mode; [`resolve`]): said in words, with
    /// an example value.
    Rule {
        /// The rule, in words.
        doc: &'static str,
        /// A valid value.
        example: &'static str,
    },
    /// No default: a new campaign must be given it (CASE, BUDGET).
    Required {
        /// A valid value.
        example: &'static str,
    },
    /// No value unless given: the setting is optional, and its absence means what the doc says.
    Absent {
        /// What its absence means.
        doc: &'static str,
        /// A valid value.
        example: &'static str,
    },
}

/// A setting's command-line flag.
#[derive(Debug, Clone, Copy)]
pub struct Flag {
    /// `--mock-speed`, or a positional argument's id (`case`).
    pub long: &'static str,
    /// One letter (`s` for `-s`), if any.
    pub short: Option<char>,
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
    /// A positional argument (its place among the positionals, from 1).
    pub position: Option<usize>,
}

impl Flag {
    /// A hidden flag taking a value.
    pub const fn value(long: &'static str, value_name: &'static str) -> Self {
        Self {
            long,
            short: None,
            value_name,
            sets: true,
            shown: false,
            alias: "",
            help: "",
            conflicts_with: "",
            position: None,
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

    /// The `index`-th positional argument (from 1) with this id, shown, named `value_name`.
    pub const fn positional(id: &'static str, value_name: &'static str, index: usize) -> Self {
        Self {
            position: Some(index),
            shown: true,
            ..Self::value(id, value_name)
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

    /// The same flag, shown in `--help` with the setting's own help.
    pub const fn visible(self) -> Self {
        Self { shown: true, ..self }
    }

    /// The same flag with a one-letter spelling.
    pub const fn short(self, letter: char) -> Self {
        Self {
            short: Some(letter),
            ..self
        }
    }

    /// Whether it takes no value.
    pub fn is_switch(&self) -> bool {
        self.value_name.is_empty()
    }

    /// The command-line argument's id: the flag without its dashes (`no-learn`), or the positional's
    /// (`case`).
    pub fn id(&self) -> &'static str {
        self.long.trim_start_matches('-')
    }
}

impl Setting {
    /// `section.key`.
    pub fn toml_key(&self) -> String {
        format!("{}.{}", self.section, self.key)
    }

    /// How errors name it: `--mock-speed (mock.speed)`, `BUDGET`, or the key alone when no flag sets it.
    pub fn names(&self) -> String {
        match &self.flag {
            Some(f) if f.position.is_some() => format!("the {}", f.long),
            Some(f) if file::FLAG_SECTIONS.contains(&self.section) => f.long.to_string(),
            Some(f) => format!("{} ({})", f.long, self.toml_key()),
            None => self.toml_key(),
        }
    }

    /// The default as a TOML value, when it is a constant.
    pub fn default_value(&self) -> Option<toml::Value> {
        match self.default {
            DefaultValue::Constant(f) => f(),
            DefaultValue::Rule { .. } | DefaultValue::Required { .. } | DefaultValue::Absent { .. } => None,
        }
    }

    /// A valid TOML value for it: the default where it is a constant.
    pub fn example(&self) -> String {
        match self.default {
            DefaultValue::Constant(f) => f().map_or_else(String::new, |v| inline(&v)),
            DefaultValue::Rule { example, .. }
            | DefaultValue::Required { example }
            | DefaultValue::Absent { example, .. } => example.to_string(),
        }
    }

    /// The flag's help: its own, or the key's naming the key.
    pub fn flag_help(&self) -> String {
        match &self.flag {
            Some(f) if !f.help.is_empty() => f.help.to_string(),
            _ if file::FLAG_SECTIONS.contains(&self.section) => self.help.to_string(),
            Some(f) if f.is_switch() => format!("Sets {} = {}.", self.toml_key(), f.sets),
            _ => format!("{} ({}).", self.help.trim_end_matches('.'), self.toml_key()),
        }
    }

    /// Whether the campaign TOML may set it (the command line's own sections it may not).
    pub fn in_file(&self) -> bool {
        !file::FLAG_SECTIONS.contains(&self.section)
    }
}

/// Every setting, in declaration order.
pub fn all() -> impl Iterator<Item = &'static Setting> {
    [
        keys::CAMPAIGN,
        keys::VEHICLES,
        keys_draw::GENERATOR,
        keys_draw::OUTPUT,
        keys_draw::SCREENING,
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

/// A new campaign of `case` and `budget` with every other setting at its default, for tests.
#[cfg(test)]
pub(crate) fn test_settings(case: &std::path::Path, budget: usize) -> CampaignSettings {
    let flags = [
        (
            find("campaign", "case"),
            toml::Value::String(case.display().to_string()),
        ),
        (find("campaign", "budget"), toml::Value::Integer(budget as i64)),
    ];
    let flags: Vec<_> = flags.into_iter().filter_map(|(s, v)| Some((s?, v))).collect();
    let request = Request::new(&Loaded::default(), &flags).expect("a request");
    CampaignSettings::resolve(&request).expect("settings")
}

#[cfg(test)]
mod tests;
