//! pymavlink (an independent MAVLink implementation) flies the mock.
//!
//! Interpreter: `$PYTHON` or `python3`. Without pymavlink the tests fail when `CI=true`, and
//! print why they skip otherwise.

use std::path::PathBuf;
use std::process::Command;
use std::time::Duration;

use crate::client::mock;

fn python() -> String {
    std::env::var("PYTHON").unwrap_or_else(|_| "python3".into())
}

/// False (after printing why) when pymavlink is missing outside CI; panics in CI.
fn pymavlink_available() -> bool {
    let ok = Command::new(python())
        .args(["-c", "import pymavlink"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        let ci = std::env::var("CI").map(|v| v == "true").unwrap_or(false);
        assert!(!ci, "pymavlink is missing for {}: pip install pymavlink", python());
        eprintln!(
            "SKIP: pymavlink not importable by {} (pip install pymavlink); CI=true makes this fail",
            python()
        );
    }
    ok
}

/// False (after printing why) when MAVSDK-Python (`mavsdk-grpc`) is missing outside CI; panics in CI.
fn mavsdk_available() -> bool {
    let ok = Command::new(python())
        .args(["-c", "import mavsdk_grpc"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !ok {
        let ci = std::env::var("CI").map(|v| v == "true").unwrap_or(false);
        assert!(
            !ci,
            "MAVSDK-Python is missing for {}: pip install mavsdk-grpc",
            python()
        );
        eprintln!(
            "SKIP: mavsdk_grpc not importable by {} (pip install mavsdk-grpc)",
            python()
        );
    }
    ok
}

fn script(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/py").join(name)
}

/// Run a script with a wall-clock bound; returns (success, combined output).
async fn run_script(args: Vec<String>, timeout: Duration) -> (bool, String) {
    let mut cmd = tokio::process::Command::new(python());
    cmd.args(&args).kill_on_drop(true);
    match tokio::time::timeout(timeout, cmd.output()).await {
        Ok(Ok(o)) => (
            o.status.success(),
            format!(
                "{}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ),
        ),
        Ok(Err(e)) => (false, format!("cannot run {}: {e}", python())),
        Err(_) => (false, "script timed out".into()),
    }
}

#[tokio::test]
async fn pymavlink_uploads_arms_and_flies_mission2() {
    if !pymavlink_available() {
        return;
    }
    let m = mock(20.0, |b| b).await;
    let port = m.local_addr().expect("addr").port();
    let args = vec![
        script("fly_mission.py").display().to_string(),
        "--port".into(),
        port.to_string(),
    ];
    let (ok, out) = run_script(args, Duration::from_secs(60)).await;
    assert!(ok, "pymavlink flight failed:\n{out}");
    assert!(out.contains("MISSION OK"), "{out}");
    m.shutdown().await.expect("stop");
}

#[tokio::test]
async fn mavsdk_uploads_downloads_arms_flies_and_lands() {
    if !mavsdk_available() {
        return;
    }
    let m = mock(5.0, |b| b).await;
    let port = m.local_addr().expect("addr").port();
    let args = vec![
        script("mavsdk_mission.py").display().to_string(),
        "--port".into(),
        port.to_string(),
    ];
    let (ok, out) = run_script(args, Duration::from_secs(120)).await;
    assert!(ok && out.contains("MAVSDK OK"), "MAVSDK flight failed:\n{out}");
    m.shutdown().await.expect("stop");
}

#[tokio::test]
async fn pymavlink_against_the_cli_with_fault_flags() {
    if !pymavlink_available() {
        return;
    }
    let mut child = tokio::process::Command::new(env!("CARGO_BIN_EXE_mock-autopilot"))
        .args([
            "--link",
            "udpin:127.0.0.1:0",
            "--speed-factor",
            "10",
            "--reject-mission",
            "4",
            "--fail-arm",
            "--seed",
            "5",
            "--loss",
            "0.05",
        ])
        .stdout(std::process::Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("start mock-autopilot");
    let stdout = child.stdout.take().expect("stdout");
    let mut lines = tokio::io::AsyncBufReadExt::lines(tokio::io::BufReader::new(stdout));
    let line = tokio::time::timeout(Duration::from_secs(20), lines.next_line())
        .await
        .expect("banner in time")
        .expect("read")
        .expect("a line");
    let port = line
        .rsplit(':')
        .next()
        .and_then(|p| p.trim().parse::<u16>().ok())
        .expect("port in banner");
    let args = vec![
        script("fly_mission.py").display().to_string(),
        "--port".into(),
        port.to_string(),
        "--expect-faults".into(),
    ];
    let (ok, out) = run_script(args, Duration::from_secs(60)).await;
    let _ = child.kill().await;
    assert!(ok, "pymavlink fault check failed:\n{out}");
    assert!(out.contains("FAULTS OK"), "{out}");
}

/// pymavlink as a pilot with a range sensor: the stick towards a wall stops near CP_DIST, and with
/// Collision Prevention off it does not (the script's own check fails).
#[tokio::test]
async fn pymavlink_sticks_towards_a_wall_stop_near_cp_dist() {
    if !pymavlink_available() {
        return;
    }
    for (cp_dist, expect_ok) in [("3", true), ("-1", false)] {
        // As PX4 v1.16, whose Collision Prevention acts at the default MPC_POS_MODE.
        let v1_16 = mock_autopilot::release::Px4Release::parse("1.16.2").expect("a release");
        let m = mock(5.0, |b| b.estimator_settle(Duration::ZERO).px4_release(v1_16)).await;
        let port = m.local_addr().expect("addr").port();
        let args: Vec<String> = [
            script("cp_stop.py").display().to_string(),
            "--url".into(),
            format!("udpout:127.0.0.1:{port}"),
            "--time-scale".into(),
            "5".into(),
            "--push".into(),
            "20".into(),
            "--cp-dist".into(),
            cp_dist.into(),
            "--expect".into(),
            "2.5".into(),
            "3.5".into(),
        ]
        .into();
        let (ok, out) = run_script(args, Duration::from_secs(90)).await;
        assert_eq!(ok, expect_ok, "CP_DIST {cp_dist}:\n{out}");
        assert!(out.contains("closest"), "{out}");
        m.shutdown().await.expect("stop");
    }
}
