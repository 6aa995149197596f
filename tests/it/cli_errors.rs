//! Bad input never panics: every malformed file gives a clear error naming the file, and exit code 2.

use prgenuav::model::TestCase;
use proptest::prelude::*;

use super::{prgenuav, repo, temp_file};

const GOOD: &str = "drone:\n  port: ros\n  params_file: missions/mission-params.csv\n  mission_file: missions/mission2.plan\n\
simulation:\n  simulator: ros\n  obstacles:\n  - size: {l: 10, w: 2, h: 20}\n    position: {x: -5, y: 20, z: 0, r: 30}\n\
test:\n  commands_file: missions/mission-commands.csv\n";

fn expect_error(name: &str, text: &str, needle: &str) {
    let (_d, path) = temp_file(name, text.as_bytes());
    let (code, out, err) = prgenuav(&["check", path.to_str().unwrap()]);
    assert_eq!(code, 2, "{name}: stdout {out} stderr {err}");
    assert!(
        err.contains(name) && err.contains(needle),
        "{name}: stderr lacks {needle:?}: {err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn good_baseline_is_valid() {
    let (_d, path) = temp_file("good.yaml", GOOD.as_bytes());
    assert_eq!(prgenuav(&["check", path.to_str().unwrap()]).0, 0);
}

#[test]
fn malformed_yaml_files() {
    expect_error("empty.yaml", "", "empty");
    expect_error("list.yaml", "- 1\n- 2\n", "expected a mapping");
    expect_error("syntax.yaml", "drone: [1,\n  x: 2\n", ":1:");
    expect_error(
        "types.yaml",
        &GOOD.replace("l: 10", "l: ten"),
        "simulation.obstacles[0].size.l",
    );
    expect_error("nan.yaml", &GOOD.replace("l: 10", "l: .nan"), "non-finite");
    expect_error("inf.yaml", &GOOD.replace("x: -5", "x: -.inf"), "non-finite");
    expect_error(
        "unknown_key.yaml",
        &GOOD.replace("simulator:", "simulatr:"),
        "simulation.simulatr",
    );
    expect_error("unknown_top.yaml", &format!("{GOOD}extra: 1\n"), "extra");
    expect_error(
        "no_mission.yaml",
        &GOOD.replace("mission2.plan", "missing.plan"),
        "drone.mission_file",
    );
    expect_error(
        "no_size.yaml",
        &GOOD.replace("size: {l: 10, w: 2, h: 20}", "size: {l: 10, w: 2}"),
        "size.h: missing",
    );
    expect_error(
        "mixed.yaml",
        &format!("{GOOD}mission:\n  commands_file: x.csv\n"),
        "spelling",
    );
    expect_error("bytes.yaml", "\u{0}\u{1}\u{2}garbage: [", "bytes.yaml");
}

#[test]
fn malformed_plan_files() {
    let plan = std::fs::read_to_string(repo().join("missions/mission2.plan")).unwrap();
    for (name, text, needle) in [
        (
            "unknown_cmd.plan",
            plan.replace("\"command\": 16", "\"command\": 54321"),
            "not a known MAV_CMD",
        ),
        ("not_json.plan", "{ this is not json".to_string(), "JSON"),
        ("no_items.plan", "{\"mission\": {}}".to_string(), "mission.items"),
        (
            "local_frame.plan",
            plan.replace("\"frame\": 3", "\"frame\": 1"),
            "global frame",
        ),
        (
            "null_lat.plan",
            plan.replacen("47.39768051930175", "null", 1),
            "lat, lon",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join(name), text).unwrap();
        let yaml = GOOD.replace("missions/mission2.plan", name);
        std::fs::write(dir.path().join("t.yaml"), yaml).unwrap();
        let (code, _, err) = prgenuav(&["check", dir.path().join("t.yaml").to_str().unwrap()]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(name) && err.contains(needle), "{name}: {err}");
    }
}

#[test]
fn malformed_flight_csv() {
    let (_d1, test) = temp_file("t.yaml", GOOD.as_bytes());
    let (_d2, flight) = temp_file("f.csv", b"timestamp,x,y,z,r\n0,0,0,0,\n100000,abc,0,0,\n");
    let (code, _, err) = prgenuav(&["distance", test.to_str().unwrap(), flight.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("f.csv:3") && err.contains("abc"), "{err}");
}

#[test]
fn distance_cli_known_answer() {
    // Straight north-east line at y = 14 passes the box centred (-5, 20) ...; compare with the library.
    let (_d1, test) = temp_file("t.yaml", GOOD.as_bytes());
    let csv = "timestamp,x,y,z,r\n0,0,0,0,\n1000000,0,0,10,\n20000000,-5,60,10,\n";
    let (_d2, flight) = temp_file("f.csv", csv.as_bytes());
    let (code, out, err) = prgenuav(&["distance", test.to_str().unwrap(), flight.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    // The path crosses the box's footprint at height 10 < 20: distance 0 and a collision.
    assert_eq!(j["min_distance_raw"], 0.0);
    assert_eq!(j["collision"], true);
    assert_eq!(j["per_obstacle"].as_array().unwrap().len(), 1);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = TestCase::parse(&text, &repo().join("random.yaml"));
    }

    #[test]
    fn random_yaml_never_panics(doc in yaml_doc()) {
        let _ = TestCase::parse(&doc, &repo().join("random.yaml"));
    }

    #[test]
    fn mutated_good_yaml_never_panics(pos in 0usize..400, ch in proptest::char::any()) {
        let mut chars: Vec<char> = GOOD.chars().collect();
        let at = pos % chars.len();
        chars[at] = ch;
        let text: String = chars.into_iter().collect();
        let _ = TestCase::parse(&text, &repo().join("random.yaml"));
    }
}

/// Random YAML built from the keys a case study uses, with values of random kinds.
fn yaml_doc() -> impl Strategy<Value = String> {
    let key = prop::sample::select(vec![
        "drone",
        "robot",
        "simulation",
        "test",
        "mission",
        "obstacles",
        "size",
        "position",
        "l",
        "w",
        "h",
        "x",
        "y",
        "z",
        "r",
        "mission_file",
        "params",
        "commands",
        "home_position",
        "port",
    ]);
    let scalar = prop_oneof![
        Just("1".to_string()),
        Just("-3.5".to_string()),
        Just(".nan".to_string()),
        Just("null".to_string()),
        Just("missions/mission1.plan".to_string()),
        Just("[1, 2, 3]".to_string()),
        Just("{a: 1}".to_string()),
        Just("\"\"".to_string()),
        "[a-z0-9 .:-]{0,12}",
    ];
    let leaf = (key.clone(), scalar).prop_map(|(k, v)| format!("{k}: {v}"));
    let block = (key, proptest::collection::vec(leaf, 0..5)).prop_map(|(k, leaves)| {
        format!(
            "{k}:\n{}",
            leaves.iter().map(|l| format!("  {l}\n")).collect::<String>()
        )
    });
    proptest::collection::vec(block, 0..5).prop_map(|b| b.join(""))
}

/// A typo in a closed set of values fails while parsing, listing the values.
#[test]
fn a_typo_in_a_value_lists_the_values() {
    for (args, values) in [
        (
            &["generate", "missions/mission2.yaml", "2", "--mode", "avoid"][..],
            "avoidance, offboard, mission",
        ),
        (
            &["generate", "missions/mission2.yaml", "2", "--judge", "2024"][..],
            "2026, 2025",
        ),
        (
            &["simulate", "missions/mission2.yaml", "--camera", "d435"][..],
            "hfs, 2019, d455",
        ),
        (
            &["simulate", "missions/mission2.yaml", "--motion", "teleport"][..],
            "px4, paper",
        ),
        (
            &["fidelity", "tests/data/hfs-flights", "--fov-estimate", "max"][..],
            "fixed, maxima",
        ),
    ] {
        let (code, _, err) = prgenuav(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("invalid value") && err.contains(values), "{args:?}: {err}");
    }
}

/// `generate --help` shows the flags a campaign is usually run with; the expert knobs are in the TOML.
#[test]
fn generate_help_shows_at_most_15_options() {
    let (code, help, err) = prgenuav(&["generate", "--help"]);
    assert_eq!(code, 0, "{err}");
    let options: Vec<&str> = help
        .lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with("--") || (l.starts_with('-') && l.chars().nth(1).is_some_and(char::is_alphabetic)))
        .collect();
    assert!(options.len() <= 15, "{} options: {options:?}", options.len());
    for flag in [
        "--seed",
        "--out",
        "--connect",
        "--no-learn",
        "--resume",
        "--config",
        "--json",
    ] {
        assert!(options.iter().any(|o| o.contains(flag)), "{flag} not shown: {help}");
    }
}

/// The old name of `--connect` still works on `generate`: hidden, same meaning.
#[test]
fn generate_takes_hfs_as_the_old_name_of_connect() {
    let (code, _, err) = prgenuav(&[
        "generate",
        "missions/mission2.yaml",
        "2",
        "--hfs",
        "mock,udpin:127.0.0.1:9",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--connect takes either `mock` or MAVLink URLs"), "{err}");
}

/// A campaign TOML with a key or a section the format does not know: refused, naming the file and the key.
#[test]
fn a_bad_campaign_toml_names_the_file_and_key() {
    for (text, needle) in [
        ("[screening]\nthreshold = 2.0\n", "threshold"),
        ("[mocks]\nspeed = 10.0\n", "mocks"),
        ("[generator]\ngap = { min = 2.0, max = 3.0 }\n", "gap"),
        ("[flight]\ntimeout_s = \"long\"\n", "timeout_s"),
    ] {
        let (_d, path) = temp_file("campaign.toml", text.as_bytes());
        let (code, _, err) = prgenuav(&[
            "generate",
            "missions/mission2.yaml",
            "2",
            "--config",
            path.to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{text}: {err}");
        assert!(err.contains("campaign.toml") && err.contains(needle), "{text}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// A campaign folder whose campaign.json stores seed 0, mission mode and a case that is not there (so a resume
/// the settings allow fails right after the check, without flying).
fn stored_campaign() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let json = r#"{"case": "missions/absent.yaml", "seed": 0, "budget": 2, "candidates": 4, "threshold_m": 3.0,
        "max_iou": 0.5, "generator": {}, "old_spelling": false, "hfs": ["mock"], "mode": "mission", "learn": true, "adapt": true}"#;
    std::fs::write(dir.path().join("campaign.json"), json).unwrap();
    dir
}

/// `--resume` refuses a flag that would change a stored setting, naming the flag and the file; flags that do
/// not change one are accepted.
#[test]
fn resume_refuses_flags_that_conflict_with_the_stored_settings() {
    let dir = stored_campaign();
    let folder = dir.path().to_str().unwrap();
    let stored = dir.path().join("campaign.json");
    let (code, _, err) = prgenuav(&["generate", "--resume", folder, "--seed", "3", "--mode", "offboard"]);
    assert_eq!(code, 2, "{err}");
    for needle in [
        format!("--seed 3 conflicts with seed 0 stored in {}", stored.display()),
        format!(
            "--mode offboard conflicts with mode mission stored in {}",
            stored.display()
        ),
        "drop it or start a new campaign".to_string(),
    ] {
        assert!(err.contains(&needle), "{needle:?} not in {err}");
    }
    let (_t, toml) = temp_file("knobs.toml", b"[screening]\nthreshold_m = 2.0\n");
    let (code, _, err) = prgenuav(&["generate", "--resume", folder, "--config", toml.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("screening.threshold_m = 2.0 in") && err.contains("knobs.toml") && err.contains("threshold_m 3"),
        "{err}"
    );
    let (code, _, err) = prgenuav(&["generate", "--resume", folder, "--no-learn"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--no-learn conflicts with learn"), "{err}");
    let (code, _, err) = prgenuav(&["generate", "--resume", folder, "--out", folder]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--out"), "{err}");
    // The same values, and flags that change no stored setting: accepted (the run then stops at the case).
    let (code, _, err) = prgenuav(&[
        "generate",
        "--resume",
        folder,
        "--seed",
        "0",
        "--mode",
        "mission",
        "--threshold",
        "3",
        "--mock-vehicles",
        "1",
        "--quiet",
        "--json",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(!err.contains("conflicts") && err.contains("absent.yaml"), "{err}");
}
