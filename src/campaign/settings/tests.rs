use std::path::{Path, PathBuf};

use super::*;
use crate::campaign::setup::{self, Ask};
use crate::judge::Judge;

fn ask() -> Ask {
    Ask {
        case: PathBuf::from("missions/mission2.yaml"),
        budget: 20,
        seed: 0,
        connect: vec!["mock".into()],
        mode: "avoidance".into(),
        judge: Judge::E2026,
        prior: None,
        runner: None,
        jobs: None,
        px4: None,
    }
}

#[test]
fn every_declared_key_parses_and_every_key_of_the_format_is_declared() {
    let text = example_toml();
    let loaded = Loaded::parse(&text, Path::new("example.toml")).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let json = serde_json::to_value(&loaded.toml).unwrap();
    for section in SECTIONS {
        let keys = json[section].as_object().unwrap();
        for (k, v) in keys {
            assert!(!v.is_null(), "[{section}] {k} is not declared");
        }
        assert_eq!(
            all().filter(|k| k.section == section).count(),
            keys.len(),
            "[{section}]"
        );
    }
    assert_eq!(
        loaded.generator_keys().len(),
        all().filter(|k| k.section == "generator").count()
    );
}

#[test]
fn every_constant_default_is_a_value_and_every_example_a_flag_value() {
    for s in all() {
        if let DefaultValue::Constant(f) = s.default {
            assert!(f().is_some(), "{}: its default is no TOML value", s.toml_key());
        }
        if let Some(f) = &s.flag
            && !f.is_switch()
        {
            let example = s.example().replace(['{', '}', ' '], "");
            let text = example
                .strip_prefix("min=")
                .map(|r| r.replace(",max=", ","))
                .unwrap_or(example.trim_matches('"').to_string());
            assert!((s.parse)(&text).is_ok(), "{} {text}", f.long);
        }
    }
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
        l.toml.generator.as_ref().map(|g| g.family),
        Some(crate::generator::Family::Extended)
    );
    assert_eq!(l.generator_keys(), ["family"]);
    let e = Loaded::parse("gap_m = { min = 2.5, max = 3.0 }\nbogus = 1\n", Path::new("g.toml")).unwrap_err();
    assert!(e.contains("bogus"), "{e}");
}

/// A value beyond `s`'s declared range, as a TOML value.
fn beyond(s: &Setting) -> Option<String> {
    let l = s.range?;
    let v = if l.whole {
        format!("{}", (l.max_here() as u64).saturating_mul(2) + 1)
    } else {
        format!("{:?}", l.max * 1.01 + 1.0)
    };
    let is_range = matches!(s.default_value(), Some(toml::Value::Table(_)));
    Some(if is_range {
        format!("{{ min = {v}, max = {v} }}")
    } else {
        v
    })
}

/// Every declared range is checked, whether the file or a flag gives the number, before the campaign runs.
#[test]
fn every_number_beyond_its_declared_range_is_refused_naming_it() {
    for s in all() {
        let Some(v) = beyond(s) else { continue };
        let text = format!("[{}]\n{} = {v}\n", s.section, s.key);
        let refused = Loaded::parse(&text, Path::new("r.toml")).and_then(|file| {
            let req = lay_over(&file, &[])?;
            check_unstored(&req.settings)?;
            setup::check(&setup::build(&ask(), &req)).map_err(|e| e.to_string())
        });
        let e = refused.expect_err(&text);
        assert!(e.contains(s.key) && e.contains("range"), "{text}: {e}");
        if let Some(f) = s.flag.filter(|f| !f.is_switch()) {
            let value = toml::from_str::<toml::Table>(&format!("v = {v}")).unwrap()["v"].clone();
            let e = lay_over(&Loaded::default(), &[(s, value)]).unwrap_err();
            assert!(e.contains(f.long) && e.contains("range"), "{}: {e}", f.long);
        }
    }
}

#[test]
fn flags_replace_the_file_and_are_recorded_by_their_stored_names() {
    let file = Loaded::parse("[mock]\nspeed = 50.0\nvehicles = 3\n", Path::new("m.toml")).unwrap();
    let speed = find("mock", "speed").unwrap();
    let req = lay_over(&file, &[(speed, toml::Value::Float(20.0))]).unwrap();
    assert_eq!(req.settings.mock.speed(), 20.0);
    assert_eq!(req.settings.mock.vehicles, Some(3));
    assert_eq!(req.given, [Given::flag("--mock-speed", false, "mock_speed")]);
    let cfg = setup::build(&ask(), &req);
    assert_eq!(cfg.mock_speed, 20.0);
    assert_eq!(setup::build(&ask(), &Requested::default()).mock_speed, 100.0);
    let cp = Ask {
        mode: "collision-prevention".into(),
        ..ask()
    };
    assert_eq!(
        setup::build(&cp, &Requested::default()).mock_speed,
        setup::CP_MOCK_SPEED
    );
    let file_only = lay_over(&file, &[]).unwrap();
    assert_eq!(setup::build(&cp, &file_only).mock_speed, 50.0, "a given speed wins");
}
