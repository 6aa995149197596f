use std::path::Path;

use clap::FromArgMatches;

use prgenuav::campaign::settings::{CampaignSettings, Loaded, example_toml};

use super::GenerateArgs;

fn settings(argv: &[&str], file: &Loaded) -> CampaignSettings {
    let m = crate::cli::command().try_get_matches_from(argv).unwrap();
    let m = m.subcommand_matches("generate").unwrap();
    let args = GenerateArgs::from_arg_matches(m).unwrap();
    let request = args.settings.request(file).unwrap();
    CampaignSettings::resolve(&request).unwrap()
}

/// docs/cli.md's example file sets every key to its documented default (or, where the default depends on
/// the campaign, to what it is for budget 20 on the mock): it must give the campaign no file gives.
#[test]
fn the_documented_defaults_are_the_defaults() {
    let argv = ["prgenuav", "generate", "missions/mission2.yaml", "20"];
    let none = settings(&argv, &Loaded::default());
    let file = Loaded::parse(&example_toml(), Path::new("example.toml")).unwrap();
    let mut all = settings(&argv, &file);
    // The defaults no value can spell: measured on each vehicle, and one per core.
    assert_eq!(all.flight.connect_time_scale, Some(1.0));
    all.flight.connect_time_scale = None;
    all.mock.vehicles = none.mock.vehicles;
    assert_eq!(none, all);
}

#[test]
fn failures_are_confirmed_by_default_wherever_flights_scatter() {
    let confirm = |extra: &[&str]| {
        let mut argv = vec!["prgenuav", "generate", "missions/mission2.yaml", "20"];
        argv.extend_from_slice(extra);
        settings(&argv, &Loaded::default()).flight.confirm
    };
    assert_eq!(confirm(&[]), 3, "the default mock profile has PX4's scatter");
    assert_eq!(confirm(&["--connect", "udpin:0.0.0.0:14540"]), 3);
    assert_eq!(confirm(&["--mock-profile", "competition"]), 1, "its flights repeat");
    assert_eq!(
        confirm(&["--mode", "mission"]),
        1,
        "the profile flies only in avoidance mode"
    );
    assert_eq!(confirm(&["--confirm", "5"]), 5);
}
