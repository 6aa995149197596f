//! docs/cli.md, rendered from the clap definition and the campaign TOML's key table, so the reference cannot
//! drift from the binary: a test renders it and fails when the file differs.

use std::fmt::Write as _;

use clap::{Arg, Command};

use prgenuav::campaign::settings::{DefaultValue, SECTIONS, all, example_toml};

/// How to bring docs/cli.md up to date.
const UPDATE: &str = "UPDATE_CLI_DOC=1 cargo test --workspace cli_doc";

/// The whole reference.
pub fn render() -> String {
    let mut cmd = super::command();
    cmd.build();
    let mut s = String::new();
    let _ = writeln!(s, "# `prgenuav` command line\n");
    let _ = writeln!(
        s,
        "<!-- Generated from the clap definitions in src/cli by `{UPDATE}`; do not edit by hand. -->\n"
    );
    let _ = writeln!(s, "{}\n", text(cmd.get_about()));
    let _ = writeln!(s, "```text\n{}\n```\n", cmd.render_usage().to_string().trim_end());
    let _ = writeln!(
        s,
        "Exit codes: 0 success, 1 the input broke a rule or a flight did not complete, 2 the input could not be \
         read or the job could not run (usage errors included).\n"
    );
    for sub in cmd.get_subcommands().filter(|c| c.get_name() != "help") {
        let _ = writeln!(
            s,
            "- [`{}`](#prgenuav-{}): {}",
            sub.get_name(),
            sub.get_name(),
            text(sub.get_about())
        );
    }
    s.push('\n');
    for sub in cmd.get_subcommands().filter(|c| c.get_name() != "help") {
        command(&mut s, sub);
    }
    campaign_toml(&mut s);
    super::limits::render(&mut s);
    s
}

fn text(t: Option<&clap::builder::StyledStr>) -> String {
    t.map(ToString::to_string).unwrap_or_default()
}

fn command(s: &mut String, c: &Command) {
    let _ = writeln!(s, "## prgenuav {}\n", c.get_name());
    let about = c.get_long_about().or(c.get_about());
    let _ = writeln!(s, "{}\n", text(about));
    let usage = c.clone().render_usage().to_string();
    let _ = writeln!(s, "```text\n{}\n```\n", usage.trim_end());
    let own = |a: &&Arg| !["help", "version"].contains(&a.get_id().as_str());
    let positionals: Vec<&Arg> = c.get_positionals().filter(own).collect();
    if !positionals.is_empty() {
        let _ = writeln!(s, "Arguments:\n");
        for a in positionals {
            argument(s, a);
        }
        s.push('\n');
    }
    let (hidden, shown): (Vec<&Arg>, Vec<&Arg>) = c
        .get_arguments()
        .filter(|a| !a.is_positional())
        .filter(own)
        .partition(|a| a.is_hide_set());
    let _ = writeln!(s, "Options:\n");
    for a in shown {
        argument(s, a);
    }
    let _ = writeln!(s, "- `-h, --help`: Print help.\n");
    if !hidden.is_empty() {
        let _ = writeln!(
            s,
            "Expert options (not in `--help`; each sets the campaign TOML key named in parentheses, see \
             [Campaign TOML](#campaign-toml)):\n"
        );
        for a in hidden {
            argument(s, a);
        }
        s.push('\n');
    }
}

fn is_switch(a: &Arg) -> bool {
    !a.get_action().takes_values()
}

/// One argument: its spelling, help, default and possible values.
fn argument(s: &mut String, a: &Arg) {
    let name = match a.get_long() {
        Some(long) if is_switch(a) => format!("--{long}"),
        Some(long) => format!("--{long} <{}>", value_name(a)),
        None => value_name(a),
    };
    let _ = write!(s, "- `{name}`: {}", sentence(&text(a.get_long_help().or(a.get_help()))));
    if let Some(aliases) = a.get_all_aliases() {
        let list: Vec<String> = aliases.iter().map(|x| format!("`--{x}`")).collect();
        let _ = write!(s, " Also accepted: {}.", list.join(", "));
    }
    let defaults: Vec<String> = a
        .get_default_values()
        .iter()
        .map(|d| d.to_string_lossy().into_owned())
        .collect();
    if !defaults.is_empty() && !is_switch(a) {
        let _ = write!(s, " Default: `{}`.", defaults.join(","));
    }
    s.push('\n');
    if !is_switch(a) {
        for v in a.get_possible_values().iter().filter(|v| !v.is_hide_set()) {
            let _ = writeln!(s, "  - `{}`: {}", v.get_name(), sentence(&text(v.get_help())));
        }
    }
}

/// Clap drops the full stop of a one-sentence help; the reference runs on after it, so put it back.
fn sentence(help: &str) -> String {
    let help = help.trim_end();
    if help.is_empty() || help.ends_with('.') {
        help.to_string()
    } else {
        format!("{help}.")
    }
}

fn value_name(a: &Arg) -> String {
    a.get_value_names()
        .and_then(|v| v.first().map(ToString::to_string))
        .unwrap_or_else(|| a.get_id().as_str().to_uppercase())
}

/// The campaign TOML's keys, section by section, and a complete example file.
fn campaign_toml(s: &mut String) {
    let _ = writeln!(
        s,
        "## Campaign TOML\n\n`generate --config FILE.toml` reads every section; `sample --config FILE.toml` reads \
         [generator] and [output]. Every key is optional: a key left out keeps its default, and a flag given on \
         the command line overrides the key. A key or section the format does not know is an error naming the \
         file and the key. A file without sections whose keys are all [generator]'s is read as [generator].\n\n\
         With `generate --resume FOLDER`, a key (or flag) whose value differs from the setting stored in \
         FOLDER/campaign.json is refused, naming both; the same value is accepted. `mock.vehicles`, \
         `flight.connect_timeout_s` and the `--instances`, `--job-timeout` and `--runner-cancel` flags are taken \
         as asked again, and `--jobs` as asked or else as the campaign last ran.\n"
    );
    for section in SECTIONS {
        let _ = writeln!(s, "### [{section}]\n");
        let _ = writeln!(s, "| key | default | flag | meaning |\n|---|---|---|---|");
        for k in all().filter(|k| k.section == section) {
            let flag = k.flag.map_or_else(|| "-".to_string(), |f| format!("`{}`", f.long));
            // A constant default is shown as code; one that depends on the campaign, as prose.
            let default = match k.default {
                DefaultValue::Constant(_) => format!("`{}`", k.example()),
                DefaultValue::Rule { doc, .. } | DefaultValue::Absent { doc, .. } => doc.to_string(),
                DefaultValue::Required { .. } => "required".to_string(),
            };
            let _ = writeln!(s, "| `{}` | {default} | {flag} | {} |", k.key, k.help);
        }
        s.push('\n');
    }
    let _ = writeln!(
        s,
        "A file setting every key (the value shown where the default depends on the campaign is an example):\n"
    );
    let _ = writeln!(s, "```toml\n{}```", example_toml());
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    /// docs/cli.md is the rendering of the current command line.
    #[test]
    fn cli_doc_is_up_to_date() {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("docs/cli.md");
        let rendered = super::render();
        if std::env::var_os("UPDATE_CLI_DOC").is_some() {
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, &rendered).unwrap();
            return;
        }
        let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            on_disk == rendered,
            "{} is out of date with the command line; update it with `{}`",
            path.display(),
            super::UPDATE
        );
    }
}
