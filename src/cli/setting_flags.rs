//! The campaign settings' flags, built from their one declaration (`prgenuav::campaign::settings`): each
//! flag's spelling, value, help and choices come from there, and what was given is handed back as the key's
//! TOML value, to be laid over the campaign TOML.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Arg, ArgAction, ArgMatches, Command};
use prgenuav::campaign::settings::{Setting, all};

/// The flags of every campaign setting (`generate`): hidden unless declared shown.
#[derive(Debug, Clone, Default)]
pub struct CampaignFlags {
    /// The flags given, each with its key's value.
    pub given: Vec<(&'static Setting, toml::Value)>,
}

/// The flags of the `[generator]` and `[output]` settings (`sample`), all shown.
#[derive(Debug, Clone, Default)]
pub struct GeneratorFlags {
    /// The flags given, each with its key's value.
    pub given: Vec<(&'static Setting, toml::Value)>,
}

fn any(_: &Setting) -> bool {
    true
}

fn generator_or_output(s: &Setting) -> bool {
    s.section == "generator" || s.section == "output"
}

/// The argument of `s`'s flag, if it has one.
fn argument(s: &'static Setting, all_shown: bool) -> Option<Arg> {
    let f = s.flag.as_ref()?;
    let mut a = Arg::new(f.id())
        .long(f.id())
        .help(s.flag_help())
        .hide(!(all_shown || f.shown));
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
    Some(if s.choices.is_empty() {
        a.value_parser(move |t: &str| parse(t))
    } else {
        let values = s
            .choices
            .iter()
            .map(|(name, help)| PossibleValue::new(*name).help(*help));
        a.value_parser(PossibleValuesParser::new(values).try_map(move |t| parse(&t)))
    })
}

fn augment(cmd: Command, keep: fn(&Setting) -> bool, all_shown: bool) -> Command {
    cmd.args(all().filter(|s| keep(s)).filter_map(|s| argument(s, all_shown)))
}

/// The flags of `keep`'s settings given in `m`.
fn given(m: &ArgMatches, keep: fn(&Setting) -> bool) -> Vec<(&'static Setting, toml::Value)> {
    let mut out = Vec::new();
    for s in all().filter(|s| keep(s)) {
        let Some(f) = &s.flag else { continue };
        let id = f.id();
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
    ($name:ident, $keep:expr, $all_shown:expr) => {
        impl clap::FromArgMatches for $name {
            fn from_arg_matches(m: &ArgMatches) -> Result<Self, clap::Error> {
                Ok(Self {
                    given: given(m, $keep),
                })
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

flags_args!(CampaignFlags, any, false);
flags_args!(GeneratorFlags, generator_or_output, true);
