use std::path::Path;

use super::*;
use crate::campaign::settings::find;

/// A campaign folder holding `settings` as campaign.json (and as its first copy).
fn folder(settings: &CampaignSettings) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    settings.save(&dir.path().join("campaign.json")).unwrap();
    settings.save(&dir.path().join(FIRST_SETTINGS_FILE)).unwrap();
    dir
}

fn asked(flags: &[(&str, &str, toml::Value)]) -> Request {
    let flags: Vec<_> = flags.iter().map(|(s, k, v)| (find(s, k).unwrap(), v.clone())).collect();
    Request::new(&Loaded::default(), &flags).unwrap()
}

fn stored() -> CampaignSettings {
    crate::campaign::settings::test_settings(Path::new("/m/mission2.yaml"), 20)
}

#[test]
fn a_fixed_setting_asked_otherwise_is_refused_by_name_and_an_equal_one_is_not() {
    let dir = folder(&stored());
    let e = resumed(dir.path(), &asked(&[("campaign", "seed", toml::Value::Integer(4))])).unwrap_err();
    let path = dir.path().join("campaign.json");
    assert!(
        e.starts_with(&format!("--seed 4 conflicts with seed 0 stored in {}", path.display())),
        "{e}"
    );
    let same = asked(&[("campaign", "seed", toml::Value::Integer(0))]);
    assert_eq!(resumed(dir.path(), &same).unwrap(), stored());
    assert_eq!(resumed(dir.path(), &asked(&[])).unwrap(), stored());
    let e = resumed(
        dir.path(),
        &asked(&[("learning", "learn", toml::Value::Boolean(false))]),
    )
    .unwrap_err();
    assert!(e.starts_with("--no-learn conflicts with learn true"), "{e}");
    let e = resumed(dir.path(), &asked(&[("output", "spelling", "old".into())])).unwrap_err();
    assert!(e.starts_with("--spelling old conflicts with spelling new"), "{e}");
}

#[test]
fn what_a_resume_takes_again_is_inherited_or_asked_anew() {
    let mut s = stored();
    s.vehicles.jobs = Some(3);
    s.mock.vehicles = 7;
    let dir = folder(&s);
    let again = resumed(dir.path(), &asked(&[])).unwrap();
    assert_eq!(again.vehicles.jobs, Some(3), "--jobs is inherited");
    assert_eq!(
        again.mock.vehicles, 3,
        "the mocks follow the inherited --jobs, not the stored count"
    );
    let more = resumed(dir.path(), &asked(&[("vehicles", "jobs", toml::Value::Integer(5))])).unwrap();
    assert_eq!((more.vehicles.jobs, more.mock.vehicles), (Some(5), 5));
}

#[test]
fn the_same_case_under_another_spelling_is_no_conflict() {
    let here = std::env::current_dir().unwrap();
    let case = here.join("missions/mission2.yaml");
    let dir = folder(&crate::campaign::settings::test_settings(&case, 20));
    let other = asked(&[("campaign", "case", "./missions/../missions/mission2.yaml".into())]);
    assert!(resumed(dir.path(), &other).is_ok());
    let e = resumed(
        dir.path(),
        &asked(&[("campaign", "case", "missions/mission3.yaml".into())]),
    )
    .unwrap_err();
    assert!(e.starts_with("CASE missions/mission3.yaml conflicts with case"), "{e}");
}

#[test]
fn a_hand_edited_campaign_json_is_named_setting_by_setting() {
    let first = stored();
    let dir = folder(&first);
    assert_eq!(changes_since_first_run(dir.path(), &first), None);
    let mut now = first.clone();
    now.campaign.budget = 30;
    now.vehicles.runner = Some("sh evil {test}".into());
    now.vehicles.jobs = Some(8);
    assert_eq!(
        changes_since_first_run(dir.path(), &now).unwrap(),
        "campaign.json differs from what the campaign's first run wrote (campaign.first.json): campaign.budget 20 -> \
         30; vehicles.runner (none) -> `sh evil {test}`"
    );
    std::fs::remove_file(dir.path().join(FIRST_SETTINGS_FILE)).unwrap();
    let said = changes_since_first_run(dir.path(), &now).unwrap();
    assert!(
        said.contains("cannot tell") && said.contains(FIRST_SETTINGS_FILE),
        "{said}"
    );
}

#[test]
fn stored_values_are_shown_as_typed() {
    assert_eq!(show(&serde_json::json!("avoidance")), "avoidance");
    assert_eq!(show(&serde_json::json!(["udpin:a", "udpin:b"])), "udpin:a,udpin:b");
    assert_eq!(show(&serde_json::json!({"min": 2.0, "max": 4.0})), "2.0,4.0");
    assert_eq!(show(&serde_json::json!(3)), "3");
}
