//! The settings' flags, built from their one declaration (`prgenuav::campaign::settings`): each flag's
//! spelling, value, help and choices come from there, and what was given is handed back as the key's TOML
//! value, to be laid over the campaign TOML. Each command takes the settings it has a use for.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Arg, ArgAction, ArgMatches, Command};
use prgenuav::campaign::settings::{Loaded, Request, Setting, all};

fn any(_: &Setting) -> bool {
    true
}

fn named(s: &Setting, keys: &[&str]) -> bool {
    keys.contains(&s.toml_key().as_str())
}

/// `evaluate`: the flights' mode, judge and seed, and whatever flies them.
fn evaluate(s: &Setting) -> bool {
    s.section == "vehicles"
        || named(
            s,
            &["campaign.mode", "campaign.judge", "campaign.seed", "mock.vehicles"],
        )
}

/// `fly`: one flight's mode, judge, timeout and anchoring, on a PX4 started here (and what simulates it, seeded)
/// or a board in the loop, or not.
fn fly(s: &Setting) -> bool {
    named(
        s,
        &[
            "campaign.mode",
            "campaign.judge",
            "flight.timeout_s",
            "flight.anchor_at_vehicle_home",
            "campaign.seed",
            "vehicles.px4",
            "vehicles.bench",
            "vehicles.sim",
            "vehicles.sim_link",
            "vehicles.hitl",
        ],
    )
}

/// `sample`: the obstacle construction, the spelling, the seed.
fn sample(s: &Setting) -> bool {
    s.section == "generator" || s.section == "output" || named(s, &["campaign.seed"])
}

/// The commands that only judge: the edition.
fn judge(s: &Setting) -> bool {
    named(s, &["campaign.judge"])
}

/// The argument of `s`'s flag, if it has one.
fn argument(s: &'static Setting, all_shown: bool) -> Option<Arg> {
    let f = s.flag.as_ref()?;
    let mut a = Arg::new(f.id()).help(s.flag_help()).hide(!(all_shown || f.shown));
    a = match f.position {
        Some(i) => a.index(i),
        None => a.long(f.id()),
    };
    if let Some(c) = f.short {
        a = a.short(c);
    }
    if !f.alias.is_empty() {
        a = a.alias(f.alias);
    }
    if !f.conflicts_with.is_empty() {
        a = a.conflicts_with(f.conflicts_with);
    }
    if f.is_switch() {
        return Some(a.action(ArgAction::SetTrue));
    }
    let parse = s.parse;
    a = a.value_name(f.value_name).action(ArgAction::Set);
    // The declaration's default, spelled as the flag takes it, so `--help` shows it; a value clap fills in
    // this way is not "given" (see `given`).
    if let Some(text) = s.default_value().as_ref().and_then(flag_text) {
        a = a.default_value(&*Box::leak(text.into_boxed_str()));
    }
    let choices = (s.choices)();
    Some(if choices.is_empty() {
        a.value_parser(Text(parse))
    } else {
        let values = choices.iter().map(|(name, help)| PossibleValue::new(*name).help(*help));
        a.value_parser(PossibleValuesParser::new(values).try_map(move |t| parse(&t)))
    })
}

/// A flag's text, refused by name when it is not UTF-8: settings are kept as text (`campaign.json`), so a path
/// that is not could never be resumed.
#[derive(Clone)]
struct Text(fn(&str) -> Result<toml::Value, String>);

impl TypedValueParser for Text {
    type Value = toml::Value;

    fn parse_ref(&self, cmd: &Command, arg: Option<&Arg>, value: &std::ffi::OsStr) -> Result<toml::Value, clap::Error> {
        let name = arg.map_or_else(String::new, |a| a.to_string());
        let Some(text) = value.to_str() else {
            return Err(clap::Error::raw(
                clap::error::ErrorKind::InvalidUtf8,
                format!(
                    "{name} {}: not UTF-8; prgenuav keeps every setting as text (campaign.json, for --resume): \
                     rename or move the file to a UTF-8 path\n",
                    std::path::Path::new(value).display()
                ),
            )
            .with_cmd(cmd));
        };
        (self.0)(text).map_err(|e| {
            clap::Error::raw(clap::error::ErrorKind::ValueValidation, format!("{name}: {e}\n")).with_cmd(cmd)
        })
    }
}

fn augment(cmd: Command, keep: fn(&Setting) -> bool, all_shown: bool) -> Command {
    cmd.args(all().filter(|s| keep(s)).filter_map(|s| argument(s, all_shown)))
}

/// A TOML default as the flag spells it: `2.0,4.0` for a range, `a,b` for a list (`None`: a table no flag
/// takes).
fn flag_text(v: &toml::Value) -> Option<String> {
    match v {
        toml::Value::String(s) => Some(s.clone()),
        toml::Value::Table(t) => Some(format!("{},{}", t.get("min")?, t.get("max")?)),
        toml::Value::Array(a) => a.iter().map(flag_text).collect::<Option<Vec<_>>>().map(|v| v.join(",")),
        other => Some(other.to_string()),
    }
}

/// The flags of `keep`'s settings given in `m` (on the command line: not the defaults clap filled in).
fn given(m: &ArgMatches, keep: fn(&Setting) -> bool) -> Vec<(&'static Setting, toml::Value)> {
    let mut out = Vec::new();
    for s in all().filter(|s| keep(s)) {
        let Some(f) = &s.flag else { continue };
        let id = f.id();
        if m.value_source(id) != Some(clap::parser::ValueSource::CommandLine) {
            continue;
        }
        if f.is_switch() {
            if m.get_flag(id) {
                out.push((s, toml::Value::Boolean(f.sets)));
            }
        } else if let Some(v) = m.get_one::<toml::Value>(id) {
            out.push((s, v.clone()));
        }
    }
    out
}

macro_rules! flags_args {
    ($(#[$m:meta])* $name:ident, $keep:expr, $all_shown:expr) => {
        $(#[$m])*
        #[derive(Debug, Clone, Default)]
        pub struct $name {
            /// The flags given, each with its key's value.
            pub given: Vec<(&'static Setting, toml::Value)>,
        }
        impl $name {
            /// The flags laid over `file`'s settings; an error names the flag.
            pub fn request(&self, file: &Loaded) -> anyhow::Result<Request> {
                Request::new(file, &self.given).map_err(anyhow::Error::msg)
            }
        }
        impl clap::FromArgMatches for $name {
            fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
                Ok(Self { given: given(m, $keep) })
            }
            fn update_from_arg_matches(&mut self, m: &ArgMatches) -> Result<(), clap::Error> {
                self.given = given(m, $keep);
                Ok(())
            }
        }
        impl clap::Args for $name {
            fn augment_args(cmd: Command) -> Command {
                augment(cmd, $keep, $all_shown)
            }
            fn augment_args_for_update(cmd: Command) -> Command {
                augment(cmd, $keep, $all_shown)
            }
        }
    };
}

flags_args!(
    /// Every campaign setting's flag (`generate`): hidden unless declared shown.
    CampaignFlags, any, false
);
flags_args!(
    /// `evaluate`'s settings flags.
    EvaluateFlags, evaluate, false
);
flags_args!(
    /// `fly`'s settings flags, all shown.
    FlyFlags, fly, true
);
flags_args!(
    /// The `[generator]` and `[output]` flags and the seed (`sample`), all shown.
    GeneratorFlags, sample, true
);
flags_args!(
    /// `--judge` alone.
    JudgeFlag, judge, true
);

impl JudgeFlag {
    /// The judge edition given, else its declared default.
    pub fn edition(&self) -> anyhow::Result<prgenuav::judge::Judge> {
        Ok(self.request(&Loaded::default())?.asked.campaign.judge())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Commands whose own argument shares a declared one's name but is another setting: `fly --connect` takes
    /// one URL (a campaign's many); `simulate` and `fidelity`, the LFS's own tools, evaluate it with the
    /// paper's model, their own ensemble and seed (and `fidelity` its own threads); `sample` draws from a case
    /// without making a campaign of it.
    const OWN: &[(&str, &str)] = &[
        ("fly", "connect"),
        ("simulate", "motion"),
        ("simulate", "ensemble"),
        ("simulate", "seed"),
        ("fidelity", "motion"),
        ("fidelity", "ensemble"),
        ("fidelity", "seed"),
        ("fidelity", "jobs"),
        ("sample", "case"),
    ];

    /// Each setting is declared once: every flag of every command named like a declared one is built from the
    /// declaration (its help, its default), and no stored type keeps a default of its own.
    #[test]
    fn every_setting_flag_comes_from_its_one_declaration() {
        let cmd = crate::cli::command();
        let mut built = 0;
        for sub in cmd.get_subcommands() {
            for a in sub.get_arguments() {
                let Some(s) = all().find(|s| s.flag.is_some_and(|f| f.id() == a.get_id().as_str())) else {
                    continue;
                };
                if OWN.contains(&(sub.get_name(), a.get_id().as_str())) {
                    continue;
                }
                built += 1;
                let help = a.get_help().map(ToString::to_string).unwrap_or_default();
                assert_eq!(help, s.flag_help(), "{} --{}", sub.get_name(), a.get_id());
                let defaults: Vec<String> = a
                    .get_default_values()
                    .iter()
                    .map(|v| v.to_string_lossy().into_owned())
                    .collect();
                // A switch sets one value; its default is its absence.
                let switch = s.flag.is_some_and(|f| f.is_switch());
                let declared: Vec<String> = (s.default_value().as_ref().and_then(flag_text).filter(|_| !switch))
                    .into_iter()
                    .collect();
                assert_eq!(defaults, declared, "{} --{}", sub.get_name(), a.get_id());
            }
        }
        assert!(built > all().filter(|s| s.flag.is_some()).count(), "{built}");
        // A serde default function is a second default beside the declaration's.
        let mut stack = vec![std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src")];
        while let Some(dir) = stack.pop() {
            for e in std::fs::read_dir(&dir).unwrap().flatten() {
                let p = e.path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|x| x == "rs") {
                    let text = std::fs::read_to_string(&p).unwrap();
                    assert!(!text.contains(concat!("serde(def", "ault = \"")), "{}", p.display());
                }
            }
        }
    }
}
