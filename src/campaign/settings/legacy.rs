//! `campaign.json` files written before the settings were sectioned (no `format` key): one flat object. The
//! rule, in one place: each old key becomes the setting `KEYS` names, as if it had been asked for; a key the
//! file lacks takes the value campaigns flew with before that key existed (`KEYS`' third column), never
//! today's default; and the settings no old file held get their declared defaults, as a new campaign would.
//! The result is resolved like any request, so an old campaign resumes with exactly the settings it began
//! with.

use serde_json::{Value, json};

use super::request::Request;
use super::stored::CampaignSettings;
use super::{Loaded, Setting, find};

/// What an old file lacking a key meant: the value campaigns flew with before the key existed.
type Absent = Option<fn() -> Value>;

/// Each old key: the setting it became, and its value when the file lacks it (`None`: every old file has it,
/// or its absence meant the setting's absence).
const KEYS: &[(&str, &str, Absent)] = &[
    ("case", "campaign.case", None),
    ("budget", "campaign.budget", None),
    ("seed", "campaign.seed", None),
    // Files from before the mode was stored flew avoidance, the only mode there was.
    ("mode", "campaign.mode", Some(|| json!("avoidance"))),
    // Before editions were stored, flights were judged by 2025's rule.
    ("judge", "campaign.judge", Some(|| json!("2025"))),
    ("prior", "campaign.prior", None),
    ("candidates", "screening.candidates", None),
    ("threshold_m", "screening.threshold_m", None),
    ("max_iou", "screening.max_iou", None),
    ("motion", "screening.motion", Some(|| json!("px4"))),
    // Before the ensemble was stored, campaigns ranked by the point prediction.
    ("ensemble", "screening.ensemble", Some(|| json!(0))),
    ("screen", "screening.screen", Some(|| json!(true))),
    // Before its key, the mocks flew at 20 x real time, free-running, with the only profile there was and no
    // gusts.
    ("mock_speed", "mock.speed", Some(|| json!(20.0))),
    ("mock_lockstep", "mock.lockstep", Some(|| json!(false))),
    ("mock_latency_ms", "mock.latency_ms", Some(|| json!(0.0))),
    ("mock_profile", "mock.profile", Some(|| json!("competition"))),
    ("mock_gust_acc_m_s2", "mock.gust_acc_m_s2", Some(|| json!(0.0))),
    (
        "anchor_at_vehicle_home",
        "flight.anchor_at_vehicle_home",
        Some(|| json!(false)),
    ),
    ("hfs_time_scale", "flight.connect_time_scale", None),
    ("flight_timeout_s", "flight.timeout_s", Some(|| json!(500.0))),
    // Before confirmation, every test flew once; before overlap, rounds were planned after they landed.
    ("confirm", "flight.confirm", Some(|| json!(1))),
    ("overlap", "flight.overlap", Some(|| json!(false))),
    // Before learning was stored, campaigns were static.
    ("learn", "learning.learn", Some(|| json!(false))),
    ("adapt", "learning.adapt", Some(|| json!(false))),
    ("min_diversity", "learning.min_diversity", Some(|| json!(0.8))),
    ("jobs", "vehicles.jobs", None),
    ("runner", "vehicles.runner", None),
];

/// The settings of an old flat `campaign.json`.
pub fn upgrade(old: Value) -> Result<CampaignSettings, String> {
    let o = old.as_object().ok_or("not a JSON object")?;
    for k in [
        "case",
        "budget",
        "seed",
        "candidates",
        "threshold_m",
        "max_iou",
        "hfs",
        "generator",
    ] {
        if !o.contains_key(k) {
            return Err(format!("missing field `{k}`"));
        }
    }
    let mut asked = Asked::default();
    for (old_key, key, absent) in KEYS {
        match (o.get(*old_key).filter(|v| !v.is_null()), absent) {
            (Some(v), _) => asked.give(key, v)?,
            (None, Some(f)) => asked.give(key, &f())?,
            (None, None) => {}
        }
    }
    // The spelling was a switch; children obeyed max_iou before their own key.
    let old_spelling = o.get("old_spelling").and_then(Value::as_bool).unwrap_or(false);
    asked.give("output.spelling", &json!(if old_spelling { "old" } else { "new" }))?;
    if let Some(child) = o.get("child_max_iou").filter(|v| !v.is_null()).or(o.get("max_iou")) {
        asked.give("learning.child_max_iou", child)?;
    }
    vehicles(o, &mut asked)?;
    for (k, v) in o.get("generator").and_then(Value::as_object).into_iter().flatten() {
        asked.give(&format!("generator.{k}"), v)?;
    }
    let request = Request::new(&Loaded::default(), &asked.0)?;
    CampaignSettings::resolve(&request)
}

/// The settings an old file gives, as flags would give them.
#[derive(Default)]
struct Asked(Vec<(&'static Setting, toml::Value)>);

impl Asked {
    fn give(&mut self, key: &str, v: &Value) -> Result<(), String> {
        let (section, name) = key.split_once('.').ok_or_else(|| format!("{key}: not a setting"))?;
        let s = find(section, name).ok_or_else(|| format!("{key}: not a setting"))?;
        let value = toml::Value::try_from(v).map_err(|e| format!("{key}: {e}"))?;
        self.0.push((s, value));
        Ok(())
    }
}

/// The old `hfs` list (`mock`, MAVLink URLs, or the stand-ins `px4` and `runner`) and `px4` object.
fn vehicles(o: &serde_json::Map<String, Value>, asked: &mut Asked) -> Result<(), String> {
    let hfs: Vec<String> =
        serde_json::from_value(o.get("hfs").cloned().unwrap_or(Value::Null)).map_err(|e| format!("hfs: {e}"))?;
    if hfs != ["px4"] && hfs != ["runner"] {
        asked.give("vehicles.connect", &json!(hfs))?;
    }
    if let Some(p) = o.get("px4").and_then(Value::as_object) {
        if let Some(b) = p.get("build") {
            asked.give("vehicles.px4", b)?;
        }
        if let Some(f) = p.get("speed_factor") {
            asked.give("vehicles.speed_factor", f)?;
        }
        asked.give("vehicles.keep_ulog", p.get("keep_ulog").unwrap_or(&json!(false)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::FlyMode;
    use crate::judge::Judge;

    fn fixture(path: &str) -> Value {
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    }

    #[test]
    fn an_old_file_reads_as_it_was_written() {
        let s = CampaignSettings::from_json(fixture("tests/data/static-killed/campaign.json")).unwrap();
        assert_eq!((s.campaign.seed, s.campaign.budget, s.screening.candidates), (3, 4, 8));
        assert_eq!((s.campaign.mode, s.campaign.judge), (FlyMode::Mission, Judge::E2026));
        assert!(s.mock.lockstep && !s.learns() && s.on_mock());
        assert_eq!((s.mock.gust_acc_m_s2, s.learning.child_max_iou), (0.1, 0.85));
    }

    #[test]
    fn a_key_an_old_file_lacks_takes_the_value_campaigns_flew_with_before_it() {
        let mut old = fixture("tests/data/static-killed/campaign.json");
        for k in [
            "mode",
            "judge",
            "mock_speed",
            "mock_lockstep",
            "mock_profile",
            "mock_gust_acc_m_s2",
            "confirm",
            "child_max_iou",
            "learn",
        ] {
            old.as_object_mut().unwrap().remove(k);
        }
        let s = CampaignSettings::from_json(old).unwrap();
        assert_eq!((s.campaign.mode, s.campaign.judge), (FlyMode::Avoidance, Judge::E2025));
        assert_eq!(
            (s.mock.speed, s.mock.lockstep, s.mock.gust_acc_m_s2),
            (20.0, false, 0.0)
        );
        assert_eq!(
            s.mock.profile,
            crate::campaign::settings::mock_profile::ProfileName::Competition
        );
        assert_eq!((s.flight.confirm, s.learning.child_max_iou), (1, s.screening.max_iou));
        assert!(!s.learning.learn);
    }

    #[test]
    fn the_old_stand_ins_for_px4_and_runner_become_their_settings() {
        let mut old = fixture("tests/data/static-killed/campaign.json");
        let o = old.as_object_mut().unwrap();
        o.insert("hfs".into(), json!(["px4"]));
        o.insert(
            "px4".into(),
            json!({"build": "/b/px4_sitl_default", "speed_factor": 10.0}),
        );
        let s = CampaignSettings::from_json(old.clone()).unwrap();
        assert_eq!(
            s.backend(),
            crate::campaign::settings::stored::Backend::Px4("/b/px4_sitl_default".as_ref())
        );
        assert_eq!((s.vehicles.speed_factor, s.vehicles.keep_ulog), (10.0, false));
        let o = old.as_object_mut().unwrap();
        o.remove("px4");
        o.insert("hfs".into(), json!(["runner"]));
        o.insert("runner".into(), json!("srun {test}"));
        let s = CampaignSettings::from_json(old).unwrap();
        assert_eq!(
            s.backend(),
            crate::campaign::settings::stored::Backend::Runner("srun {test}")
        );
    }

    #[test]
    fn an_old_file_missing_a_key_it_always_had_is_refused_by_name() {
        let mut old = fixture("tests/data/static-killed/campaign.json");
        old.as_object_mut().unwrap().remove("budget");
        let e = CampaignSettings::from_json(old).unwrap_err();
        assert!(e.contains("budget"), "{e}");
    }
}
