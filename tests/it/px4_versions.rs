//! `--px4` builds of different PX4 releases without PX4: fake build folders whose version header names the
//! release. What a release cannot fly, and a release prgenuav has not checked, is refused with exit 2 before
//! any PX4 starts. Runs in normal CI.

use super::px4_fake::fake_build_tagged;
use super::{test_file, valid_pair};

/// A `bin/px4` that leaves a mark beside the build folder if anything starts it.
fn marking(mark: &std::path::Path) -> String {
    format!("touch '{}'\nexit 3", mark.display())
}

#[test]
fn avoidance_on_a_v1_16_build_is_refused_naming_the_version_and_the_modes_that_work() {
    let tmp = tempfile::tempdir().unwrap();
    let mark = tmp.path().join("started");
    let build = fake_build_tagged(&marking(&mark), "v1.16.2");
    let b = build.path().to_str().unwrap();
    let (_d, test) = test_file(2, valid_pair());
    let t = test.to_str().unwrap();
    for args in [
        vec!["fly", t, "--px4", b, "--mode", "avoidance", "--quiet"],
        vec!["fly", t, "--px4", b, "--quiet"],
    ] {
        let (code, _, err) = super::prgenuav(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.contains("--mode avoidance: PX4 v1.16.2 has no obstacle-avoidance interface")
                && err.contains("modes that work on PX4 1.16: offboard, mission"),
            "{args:?}: {err}"
        );
    }
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    let (code, _, err) = super::prgenuav(&[
        "generate",
        "missions/mission2.yaml",
        "3",
        "--px4",
        b,
        "--no-screen",
        "--quiet",
        "--out",
        o,
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("PX4 v1.16.2 has no obstacle-avoidance interface"), "{err}");
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0, "nothing written");
    assert!(!mark.exists(), "no PX4 was started");
}

#[test]
fn a_build_of_an_unchecked_or_unreadable_version_is_refused_naming_what_was_read() {
    let tmp = tempfile::tempdir().unwrap();
    let mark = tmp.path().join("started");
    let (_d, test) = test_file(2, valid_pair());
    let t = test.to_str().unwrap();
    for (tag, expected) in [
        ("v1.18.0-beta1", "PX4 v1.18.0-beta1 (read as 1.18) has not been checked"),
        ("v1.13.3", "PX4 v1.13.3 (read as 1.13) has not been checked"),
        ("", "PX4_GIT_TAG_STR \"\", not a version"),
    ] {
        let build = fake_build_tagged(&marking(&mark), tag);
        let b = build.path().to_str().unwrap();
        let (code, _, err) = super::prgenuav(&["fly", t, "--px4", b, "--mode", "offboard", "--quiet"]);
        assert_eq!(code, 2, "{tag}: {err}");
        assert!(
            err.contains(expected) && err.contains("build_git_version.h"),
            "{tag}: {err}"
        );
    }
    assert!(!mark.exists(), "no PX4 was started");
}
