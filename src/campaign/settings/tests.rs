use std::path::Path;

use super::*;

/// A new campaign's request: CASE and BUDGET, and `flags`.
fn request(flags: Vec<(&'static Setting, toml::Value)>, file: &Loaded) -> Result<Request, String> {
    let mut all = vec![
        (
            find("campaign", "case").unwrap(),
            toml::Value::String("missions/mission2.yaml".into()),
        ),
        (find("campaign", "budget").unwrap(), toml::Value::Integer(20)),
    ];
    all.extend(flags);
    Request::new(file, &all)
}

#[test]
fn every_declared_key_parses_and_every_key_of_the_format_is_declared() {
    let text = example_toml();
    let loaded = Loaded::parse(&text, Path::new("example.toml")).unwrap_or_else(|e| panic!("{e}\n{text}"));
    let asked = request::Asked::typed(&loaded.raw).unwrap();
    let json = serde_json::to_value(&asked).unwrap();
    for section in SECTIONS.into_iter().filter(|s| *s != "generator") {
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
            let example = s.example().replace(['{', '}', ' ', '[', ']'], "");
            let text = example
                .strip_prefix("min=")
                .map(|r| r.replace(",max=", ","))
                .unwrap_or(example.trim_matches('"').replace('"', ""));
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
    let e = Loaded::parse("[screening]\nmotion = \"pixhawk\"\n", p).unwrap_err();
    assert!(e.contains("pixhawk") && e.contains("px4"), "{e}");
    let e = Loaded::parse("[campaign]\nseed = 3\n", p).unwrap_err();
    assert!(e.contains("command line"), "{e}");
}

#[test]
fn a_file_of_generator_keys_alone_is_the_generator_section() {
    let l = Loaded::parse("family = \"extended\"\n", Path::new("g.toml")).unwrap();
    let r = Request::new(&l, &[]).unwrap();
    assert_eq!(r.generator().family, crate::generator::Family::Extended);
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
        if s.in_file() {
            let text = format!("[{}]\n{} = {v}\n", s.section, s.key);
            let refused = Loaded::parse(&text, Path::new("r.toml"))
                .and_then(|file| request(vec![], &file))
                .and_then(|r| CampaignSettings::resolve(&r))
                .and_then(|c| c.check());
            let e = refused.expect_err(&text);
            assert!(e.contains(s.key) && e.contains("range"), "{text}: {e}");
        }
        if let Some(f) = s.flag.filter(|f| !f.is_switch()) {
            let value = toml::from_str::<toml::Table>(&format!("v = {v}")).unwrap()["v"].clone();
            let e = Request::new(&Loaded::default(), &[(s, value)]).unwrap_err();
            let named = if f.position.is_some() { s.key } else { f.long };
            assert!(e.contains(named) && e.contains("range"), "{}: {e}", f.long);
        }
    }
}

#[test]
fn flags_replace_the_file_and_are_recorded_as_given() {
    let file = Loaded::parse("[mock]\nspeed = 50.0\nvehicles = 3\n", Path::new("m.toml")).unwrap();
    let speed = find("mock", "speed").unwrap();
    let req = request(vec![(speed, toml::Value::Float(20.0))], &file).unwrap();
    assert_eq!(req.asked.mock.speed, Some(20.0));
    assert_eq!(req.asked.mock.vehicles, Some(3));
    let given: Vec<(String, Option<String>)> = (req.given.iter())
        .map(|g| (g.setting.toml_key(), g.file.clone()))
        .collect();
    assert_eq!(
        given,
        [
            ("campaign.case".to_string(), None),
            ("campaign.budget".to_string(), None),
            ("mock.speed".to_string(), None),
            ("mock.vehicles".to_string(), Some("m.toml".to_string())),
        ]
    );
    let s = CampaignSettings::resolve(&req).unwrap();
    assert_eq!((s.mock.speed, s.mock.vehicles), (20.0, 3));
}

#[test]
fn campaign_json_is_the_settings_and_reads_back_as_they_were() {
    let dir = tempfile::tempdir().unwrap();
    let s = CampaignSettings::resolve(&request(vec![], &Loaded::default()).unwrap()).unwrap();
    s.save(&dir.path().join("campaign.json")).unwrap();
    assert_eq!(CampaignSettings::load(dir.path()).unwrap(), s);
    let json = s.to_json().unwrap();
    assert_eq!(json["format"], json::FORMAT);
    let mut newer = json.clone();
    newer["format"] = serde_json::json!(json::FORMAT + 1);
    let e = CampaignSettings::from_json(newer).unwrap_err();
    assert!(e.contains("newer prgenuav"), "{e}");
    let mut stray = json;
    stray["screening"]["thresold_m"] = serde_json::json!(2.0);
    assert!(CampaignSettings::from_json(stray).unwrap_err().contains("thresold_m"));
}

#[test]
fn a_format_2_campaign_reads_as_flown_on_sih_with_no_board() {
    let s = CampaignSettings::resolve(&request(vec![], &Loaded::default()).unwrap()).unwrap();
    let mut old = s.to_json().unwrap();
    old["format"] = serde_json::json!(2);
    for key in ["sim", "sim_link", "hitl", "bench"] {
        old["vehicles"].as_object_mut().unwrap().remove(key);
    }
    let read = CampaignSettings::from_json(old).unwrap();
    assert_eq!(read, s);
    assert_eq!(
        (read.vehicles.sim, read.vehicles.sim_link, read.vehicles.hitl),
        (crate::bridge::VehicleSim::Sih, crate::bridge::SimLink::Tcp, None)
    );
}

#[test]
fn a_format_3_campaign_reads_as_flown_on_no_bench() {
    let s = CampaignSettings::resolve(&request(vec![], &Loaded::default()).unwrap()).unwrap();
    let mut old = s.to_json().unwrap();
    old["format"] = serde_json::json!(3);
    old["vehicles"].as_object_mut().unwrap().remove("bench");
    let read = CampaignSettings::from_json(old).unwrap();
    assert_eq!((read.vehicles.bench, &read), (crate::bridge::Bench::Plain, &s));
}

#[test]
fn the_competition_bench_flies_the_iris_on_px4_and_refuses_sih() {
    let bench = (
        find("vehicles", "bench").unwrap(),
        toml::Value::String("competition".into()),
    );
    let sim = |v: &str| (find("vehicles", "sim").unwrap(), toml::Value::String(v.into()));
    let px4 = (
        find("vehicles", "px4").unwrap(),
        toml::Value::String("/b/px4_sitl_default".into()),
    );
    let e = request(vec![bench.clone()], &Loaded::default())
        .and_then(|r| r.check())
        .unwrap_err();
    assert!(e.contains("--bench") && e.contains("--px4"), "{e}");
    let r = request(vec![px4.clone(), bench.clone()], &Loaded::default()).unwrap();
    r.check().unwrap();
    let s = CampaignSettings::resolve(&r).unwrap();
    s.check().unwrap();
    assert_eq!(s.vehicles.sim, crate::bridge::VehicleSim::Iris, "the bench's simulator");
    let r = request(vec![px4.clone(), bench, sim("sih")], &Loaded::default()).unwrap();
    let e = CampaignSettings::resolve(&r).unwrap().check().unwrap_err();
    assert!(e.contains("--sim iris"), "{e}");
    let plain = CampaignSettings::resolve(&request(vec![px4], &Loaded::default()).unwrap()).unwrap();
    assert_eq!(plain.vehicles.sim, crate::bridge::VehicleSim::Sih);
}

#[test]
fn a_suite_flown_on_the_competition_bench_is_evaluated_on_it_unless_another_bench_is_asked() {
    use super::evaluation::EvaluationSettings;
    let value = |key: &str, v: &str| (find("vehicles", key).unwrap(), toml::Value::String(v.into()));
    let px4 = value("px4", "/b/px4_sitl_default");
    let suite = request(vec![px4.clone(), value("bench", "competition")], &Loaded::default()).unwrap();
    let suite = CampaignSettings::resolve(&suite).unwrap();
    let again = |asked: Vec<(&'static super::Setting, toml::Value)>| {
        let r = request(asked, &Loaded::default()).unwrap();
        EvaluationSettings::resolve(&r, Some(&suite)).unwrap().vehicles
    };
    let v = again(vec![px4.clone()]);
    assert_eq!(
        (v.bench, v.sim),
        (crate::bridge::Bench::Competition, crate::bridge::VehicleSim::Iris)
    );
    let v = again(vec![px4, value("bench", "plain")]);
    assert_eq!(
        (v.bench, v.sim),
        (crate::bridge::Bench::Plain, crate::bridge::VehicleSim::Sih)
    );
}

#[test]
fn the_iris_simulator_and_boards_are_refused_where_they_cannot_fly() {
    let sim = |v: &str| (find("vehicles", "sim").unwrap(), toml::Value::String(v.into()));
    let link = |v: &str| (find("vehicles", "sim_link").unwrap(), toml::Value::String(v.into()));
    let e = request(vec![sim("iris")], &Loaded::default())
        .and_then(|r| r.check())
        .unwrap_err();
    assert!(e.contains("need --px4"), "{e}");
    let px4 = (
        find("vehicles", "px4").unwrap(),
        toml::Value::String("/b/px4_sitl_default".into()),
    );
    let r = request(vec![px4.clone(), link("serial")], &Loaded::default()).unwrap();
    r.check().unwrap();
    let e = CampaignSettings::resolve(&r).unwrap().check().unwrap_err();
    assert!(e.contains("give --sim iris too"), "{e}");
    let r = request(vec![px4, link("serial"), sim("iris")], &Loaded::default()).unwrap();
    CampaignSettings::resolve(&r).unwrap().check().unwrap();
    let hitl = |v: &str| {
        (
            find("vehicles", "hitl").unwrap(),
            <Vec<String> as SettingValue>::parse(v).unwrap(),
        )
    };
    let r = request(
        vec![hitl("serial:/dev/ttyACM0:921600,serial:/dev/ttyACM1:921600")],
        &Loaded::default(),
    )
    .unwrap();
    let s = CampaignSettings::resolve(&r).unwrap();
    s.check().unwrap();
    assert!(matches!(s.backend(), Backend::Hitl(b) if b.len() == 2));
    let r = request(vec![hitl("serial:/dev/ttyACM0:9600")], &Loaded::default()).unwrap();
    let e = CampaignSettings::resolve(&r).unwrap().check().unwrap_err();
    assert!(e.contains("too slow for HIL"), "{e}");
}

/// Each setting's default is declared once: every key `campaign.json` holds is a declared setting's, so no
/// default can hide in the stored type; and no declared default is a second spelling of another's.
#[test]
fn every_stored_key_is_a_declared_setting() {
    let s = CampaignSettings::resolve(&request(vec![], &Loaded::default()).unwrap()).unwrap();
    let json = serde_json::to_value(&s).unwrap();
    let mut stored = Vec::new();
    for (section, keys) in json.as_object().unwrap() {
        for key in keys.as_object().unwrap().keys() {
            stored.push(format!("{section}.{key}"));
        }
    }
    let declared: Vec<String> = all().map(Setting::toml_key).collect();
    assert_eq!(stored.len(), declared.len());
    for k in &stored {
        assert!(declared.contains(k), "{k} is stored but not declared");
    }
    let mut flags: Vec<&str> = all().filter_map(|s| s.flag.map(|f| f.long)).collect();
    let n = flags.len();
    flags.sort();
    flags.dedup();
    assert_eq!(flags.len(), n, "a flag is declared twice");
}
