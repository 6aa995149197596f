//! `--px4` builds of different PX4 releases without PX4: fake build folders whose version header names the
//! release. What a release cannot fly, and a release prgenuav has not checked, is refused with exit 2 before
//! any PX4 starts. Runs in normal CI.

use std::time::Duration;

use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, Status, fly};

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
                && err.contains("modes that work on PX4 1.16: offboard, mission, collision-prevention"),
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

/// The mock autopilot acting as PX4 `release` on an ephemeral port, and the bridge's address for it.
async fn mock_as(release: &str, speed: f64) -> (mock_autopilot::MockHandle, String) {
    let release = mock_autopilot::release::Px4Release::parse(release).expect("a release");
    let m = mock_autopilot::MockAutopilot::builder()
        .link(mock_autopilot::LinkSpec::UdpIn("127.0.0.1:0".parse().expect("addr")))
        .speed_factor(mock_autopilot::SpeedFactor::Times(speed))
        .px4_release(release)
        .spawn()
        .await
        .expect("mock starts");
    let port = m.local_addr().expect("udp").port();
    (m, format!("udpout:127.0.0.1:{port}"))
}

/// Mission 2 with two boxes and a case-study parameter file that sets COM_OBS_AVOID, as competition
/// parameter files do.
fn with_avoidance_param() -> prgenuav::model::TestCase {
    let mut test = super::case(2).with_obstacles(valid_pair());
    test.params.push(prgenuav::model::Param {
        name: "COM_OBS_AVOID".into(),
        value: 1.0,
    });
    test
}

async fn fly_on_mock(url: &str, mode: FlyMode, speed: f64) -> FlightReport {
    let opts = FlyOptions {
        connect: url.into(),
        mode,
        time_scale: speed,
        heartbeat_wait_s: 20.0,
        ..FlyOptions::default()
    };
    tokio::time::timeout(
        Duration::from_secs(90),
        fly(&with_avoidance_param(), &opts, CancelToken::new()),
    )
    .await
    .expect("bounded")
    .expect("flight runs")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn avoidance_on_a_vehicle_reporting_v1_16_is_refused_before_anything_is_uploaded_or_armed() {
    let (mock, url) = mock_as("1.16.2", 20.0).await;
    let r = fly_on_mock(&url, FlyMode::Avoidance, 20.0).await;
    let state = mock.state();
    mock.shutdown().await.expect("mock stops");
    assert_eq!(r.status, Status::Rejected, "{:?}", r.reason);
    let reason = r.reason.unwrap_or_default();
    assert!(
        reason.contains("--mode avoidance: PX4 1.16.2 has no obstacle-avoidance interface")
            && reason.contains("modes that work on PX4 1.16: offboard, mission, collision-prevention"),
        "{reason}"
    );
    assert_eq!(
        (state.mission_items, state.armed, r.samples > 0),
        (0, false, false),
        "{state:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mission_mode_on_a_vehicle_reporting_v1_16_lands_and_skips_com_obs_avoid_with_a_warning() {
    let (mock, url) = mock_as("v1.16.2", 20.0).await;
    let r = fly_on_mock(&url, FlyMode::Mission, 20.0).await;
    mock.shutdown().await.expect("mock stops");
    assert!(r.status.completed(), "{:?} {:?}", r.status, r.reason);
    assert!(r.min_distance.is_some());
    assert!(
        r.warnings.iter().any(|w| w
            .contains("case-study parameter COM_OBS_AVOID not set: PX4 1.16.2 has no obstacle-avoidance interface")),
        "{:?}",
        r.warnings
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_vehicle_reporting_an_unchecked_release_is_refused_naming_it() {
    let (mock, url) = mock_as("1.18.0", 20.0).await;
    let r = fly_on_mock(&url, FlyMode::Offboard, 20.0).await;
    let state = mock.state();
    mock.shutdown().await.expect("mock stops");
    assert_eq!(r.status, Status::Rejected, "{:?}", r.reason);
    let reason = r.reason.unwrap_or_default();
    assert!(
        reason.contains("the vehicle reports PX4 1.18.0 (read as 1.18) has not been checked with prgenuav"),
        "{reason}"
    );
    assert_eq!((state.mission_items, state.armed), (0, false), "{state:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_vehicle_reporting_v1_14_keeps_its_avoidance_parameter() {
    let (mock, url) = mock_as("1.14.0", 20.0).await;
    let r = fly_on_mock(&url, FlyMode::Mission, 20.0).await;
    mock.shutdown().await.expect("mock stops");
    assert!(r.status.completed(), "{:?} {:?}", r.status, r.reason);
    assert!(
        !r.warnings.iter().any(|w| w.contains("COM_OBS_AVOID")),
        "{:?}",
        r.warnings
    );
}

#[test]
fn the_competition_bench_is_refused_on_a_release_it_was_not_checked_on_and_with_sih() {
    let tmp = tempfile::tempdir().unwrap();
    let mark = tmp.path().join("started");
    let build = fake_build_tagged(&marking(&mark), "v1.14.0");
    let b = build.path().to_str().unwrap();
    let (_d, test) = test_file(2, valid_pair());
    let t = test.to_str().unwrap();
    let (code, _, err) = super::prgenuav(&["fly", t, "--px4", b, "--bench", "competition", "--quiet"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--bench competition was checked on PX4 v1.12") && err.contains("v1.14.0"),
        "{err}"
    );
    let out = tempfile::tempdir().unwrap();
    let o = out.path().to_str().unwrap();
    let generate = |extra: &[&str]| {
        let mut args = vec![
            "generate",
            "missions/mission2.yaml",
            "3",
            "--px4",
            b,
            "--no-screen",
            "--quiet",
            "--out",
            o,
        ];
        args.extend_from_slice(extra);
        super::prgenuav(&args)
    };
    let (code, _, err) = generate(&["--bench", "competition"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("v1.14.0"), "{err}");
    let v112 = fake_build_tagged(&marking(&mark), "v1.12.3");
    let b12 = v112.path().to_str().unwrap();
    let (code, _, err) = super::prgenuav(&[
        "fly",
        t,
        "--px4",
        b12,
        "--bench",
        "competition",
        "--sim",
        "sih",
        "--quiet",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("give --sim iris or leave --sim out"), "{err}");
    let (code, _, err) = super::prgenuav(&["fly", t, "--bench", "competition", "--quiet"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("need --px4"), "{err}");
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0, "nothing written");
    assert!(!mark.exists(), "no PX4 was started");
}
