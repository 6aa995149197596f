use std::path::Path;

use clap::FromArgMatches;

use prgenuav::campaign::settings::{Loaded, Requested, example_toml};

use super::{Args, build, request};
use prgenuav::campaign::setup::resume::show;

fn requested(argv: &[&str], file: &Loaded) -> (Args, Requested) {
    let m = crate::cli::command().try_get_matches_from(argv).unwrap();
    let m = m.subcommand_matches("generate").unwrap();
    let args = Args::from_arg_matches(m).unwrap();
    let req = request(&args, m, file).unwrap().req;
    (args, req)
}

/// docs/cli.md's example file sets every key to its documented default (or, where the default depends on
/// the campaign, to what it is for budget 20 on the mock): it must give the campaign no file gives.
#[test]
fn the_documented_defaults_are_the_defaults() {
    let argv = ["prgenuav", "generate", "missions/mission2.yaml", "20"];
    let (args, none) = requested(&argv, &Loaded::default());
    let file = Loaded::parse(&example_toml(), Path::new("example.toml")).unwrap();
    let (_, all) = requested(&argv, &file);
    let case = || args.case.clone().unwrap();
    let mut a = serde_json::to_value(build(case(), 20, &args, &none)).unwrap();
    let mut b = serde_json::to_value(build(case(), 20, &args, &all)).unwrap();
    // The one default no value can spell: measured on each vehicle.
    assert_eq!(b["hfs_time_scale"], 1.0);
    a["hfs_time_scale"] = serde_json::Value::Null;
    b["hfs_time_scale"] = serde_json::Value::Null;
    assert_eq!(a, b);
    // Every key campaign.json stores, and CASE and BUDGET.
    assert_eq!(
        all.given.len(),
        prgenuav::campaign::settings::all()
            .filter(|s| !s.stored.is_empty())
            .count()
            + 2
    );
    assert!(none.given.iter().all(|g| g.key == "case" || g.key == "budget"));
}

#[test]
fn stored_values_are_shown_as_typed() {
    assert_eq!(show(&serde_json::json!("avoidance")), "avoidance");
    assert_eq!(show(&serde_json::json!(["udpin:a", "udpin:b"])), "udpin:a,udpin:b");
    assert_eq!(show(&serde_json::json!({"min": 2.0, "max": 4.0})), "2.0,4.0");
    assert_eq!(show(&serde_json::json!(3)), "3");
}

#[test]
fn failures_are_confirmed_by_default_wherever_flights_scatter() {
    let confirm = |extra: &[&str]| {
        let mut argv = vec!["prgenuav", "generate", "missions/mission2.yaml", "20"];
        argv.extend_from_slice(extra);
        let (args, req) = requested(&argv, &Loaded::default());
        build(args.case.clone().unwrap(), 20, &args, &req).confirm
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
