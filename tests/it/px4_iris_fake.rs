//! `--px4 BUILD --sim iris` without PX4: the fake build's `bin/px4` runs this test binary's [`fake_px4`],
//! which acts as PX4 SITL in external-simulator mode: it checks its environment (`PX4_SIM_MODEL`, no
//! `PX4_SIMULATOR`), connects to the simulator's TCP port 4560+i as PX4 does, answers each HIL_SENSOR with
//! HIL_ACTUATOR_CONTROLS, says its startup script returned after the first one, and flies an embedded mock
//! autopilot on instance i's UDP ports. Checked: both run and stop with the flight (the port freed), a
//! simulator that loses PX4 ends the flight `link_lost`, a PX4 dying after boot is retried on a fresh pair
//! and not charged, a taken port is said naming it, and a killed prgenuav leaves nothing behind.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use mavlink::dialects::common::MavMessage;
use mavlink::{AsyncMavlinkReader, MavHeader};
use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
use prgenuav::bridge::hil::sitl::{IrisSitl, IrisSpec};
use prgenuav::bridge::sitl::Px4Build;
use prgenuav::bridge::sitl::slot::{self, Slot};
use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, SimLink, Status, VehicleSim, fly};
use prgenuav::campaign::fly::px4::{Px4Settings, Px4Vehicle};
use prgenuav::campaign::fly::vehicle::Vehicle;
use prgenuav::campaign::ground::flight_status::FlightStatus;
use simulator::hil::messages::actuator_controls;

use super::px4_fake::{children_of, fake_build_tagged, gone};
use super::{case, test_file, valid_pair};

/// The environment variable that makes [`fake_px4`] act: PX4's instance number.
const FAKE: &str = "PRGENUAV_FAKE_PX4";

/// A fake build of `tag` whose `bin/px4` is [`fake_px4`] in `mode` (`fly`, `lose:SECS`, `die`), with the
/// external-simulator module's command (`px4-simulator_mavlink`, v1.12's `px4-simulator`).
fn fake_iris_build(tag: &str, mode: &str, pids: &Path) -> tempfile::TempDir {
    let exe = std::env::current_exe().expect("the test binary");
    let script = format!(
        "echo $$ >> '{}'\nexec env {FAKE}=\"$3\" PRGENUAV_FAKE_PX4_MODE={mode} '{}' px4_iris_fake::fake_px4 --exact \
         --ignored --nocapture --test-threads=1",
        pids.display(),
        exe.display()
    );
    let build = fake_build_tagged(&script, tag);
    let module = if tag.starts_with("v1.12") {
        "px4-simulator"
    } else {
        "px4-simulator_mavlink"
    };
    std::fs::write(build.path().join("bin").join(module), "").expect("module");
    build
}

/// PX4 SITL in external-simulator mode, as far as prgenuav sees it (the body of a fake `bin/px4`).
#[test]
#[ignore = "the fake PX4 of px4_iris_fake's builds, run as their bin/px4"]
fn fake_px4() {
    let Some(instance) = std::env::var(FAKE).ok().and_then(|i| i.parse::<u16>().ok()) else {
        return;
    };
    let model = std::env::var("PX4_SIM_MODEL").unwrap_or_default();
    if !["none_iris", "iris"].contains(&model.as_str()) || std::env::var_os("PX4_SIMULATOR").is_some() {
        println!("ERROR [fake px4] not external-simulator mode: PX4_SIM_MODEL={model:?}");
        std::process::exit(3);
    }
    let mode = std::env::var("PRGENUAV_FAKE_PX4_MODE").unwrap_or_default();
    let rt = tokio::runtime::Runtime::new().expect("runtime");
    rt.block_on(serve(instance, &mode));
}

async fn serve(instance: u16, mode: &str) {
    let port = 4560 + instance;
    println!("INFO  [simulator_mavlink] Waiting for simulator to accept connection on TCP port {port}");
    let t0 = Instant::now();
    let stream = loop {
        match tokio::net::TcpStream::connect(("127.0.0.1", port)).await {
            Ok(s) => break s,
            Err(_) if t0.elapsed() < Duration::from_secs(30) => tokio::time::sleep(Duration::from_millis(100)).await,
            Err(e) => panic!("no simulator on {port}: {e}"),
        }
    };
    let (read, mut write) = stream.into_split();
    let mut reader = AsyncMavlinkReader::new(read);
    let header = MavHeader {
        system_id: 1,
        component_id: 1,
        sequence: 0,
    };
    let mut booted = false;
    let mut mock = None;
    let lose_after = mode
        .strip_prefix("lose:")
        .and_then(|s| s.parse().ok())
        .map(Duration::from_secs);
    let t0 = Instant::now();
    loop {
        if lose_after.is_some_and(|d| t0.elapsed() > d) {
            // PX4's end of the HIL link goes, and PX4 with it (frozen in lockstep: silent).
            drop(write);
            if let Some(m) = mock.take() {
                let _ = mock_autopilot::MockHandle::shutdown(m).await;
            }
            tokio::time::sleep(Duration::from_secs(120)).await;
            return;
        }
        let Ok((_, msg)) = reader.read_any_message::<MavMessage>().await else {
            return;
        };
        let MavMessage::HIL_SENSOR(s) = msg else { continue };
        let answer = actuator_controls(s.time_usec, &[0.0; 4], false);
        if mavlink::write_v2_msg_async(&mut write, header, &answer).await.is_err() {
            return;
        }
        if !booted {
            booted = true;
            println!("INFO  [init] Startup script returned successfully");
            if mode == "die" {
                tokio::time::sleep(Duration::from_millis(500)).await;
                std::process::exit(1);
            }
            let m = MockAutopilot::builder()
                .link(LinkSpec::Px4Sitl { instance })
                .speed_factor(SpeedFactor::Times(5.0))
                .spawn()
                .await
                .expect("the fake's autopilot");
            mock = Some(m);
        }
    }
}

/// A free slot of instance 3 or above whose simulator port is free too.
fn iris_slot() -> Slot {
    slot::claim_with(3, VehicleSim::Iris).unwrap_or_else(|e| panic!("{e}"))
}

fn spec(build: &Path, instance: u8) -> IrisSpec {
    IrisSpec {
        build: Px4Build::open(build).expect("a build"),
        instance,
        home: case(2).home,
        heading_deg: 0.0,
        seed: 7,
        speed_factor: 5.0,
        link: SimLink::Tcp,
        paced: false,
        boot_timeout: Duration::from_secs(30),
    }
}

/// Starts the pair on `rt`, flies mission 2 in `mission` mode, stops the pair; the report and what the
/// simulator said.
fn fly_pair(build: &Path, instance: u8) -> (prgenuav::bridge::FlightReport, Option<String>, String) {
    let rt = tokio::runtime::Runtime::new().expect("runtime");
    let mut iris =
        IrisSitl::start(rt.handle(), &spec(build, instance), &AtomicBool::new(false)).expect("the pair starts");
    let opts = FlyOptions {
        connect: iris.px4.url(),
        mode: FlyMode::Mission,
        time_scale: 5.0,
        detect_time_scale: true,
        heartbeat_wait_s: 60.0,
        timeout_s: 400.0,
        ..FlyOptions::default()
    };
    let test = case(2).with_obstacles(valid_pair());
    let report = rt
        .block_on(async { tokio::time::timeout(Duration::from_secs(180), fly(&test, &opts, CancelToken::new())).await })
        .expect("the flight ends in time")
        .expect("the flight runs");
    let lost = iris.sim_failure();
    let summary = iris.finish().map(|s| s.to_string()).unwrap_or_default();
    (report, lost, summary)
}

fn port_free(instance: u8) -> bool {
    std::net::TcpListener::bind(("127.0.0.1", 4560 + u16::from(instance))).is_ok()
}

#[test]
fn px4_in_external_simulator_mode_flies_beside_the_simulator_and_both_stop_with_the_flight() {
    let tmp = tempfile::tempdir().unwrap();
    let build = fake_iris_build("v1.14.0", "fly", &tmp.path().join("pids"));
    let slot = iris_slot();
    let (r, lost, summary) = fly_pair(build.path(), slot.instance());
    assert!(r.status.completed(), "{:?} {:?}", r.status, r.reason);
    assert!(
        r.min_distance.is_some() && r.samples > 100,
        "judged: {:?}",
        r.min_distance
    );
    assert_eq!(lost, None);
    assert!(
        summary.contains("tcp lockstep, seed 7") && !summary.contains("ended"),
        "{summary}"
    );
    assert!(
        port_free(slot.instance()),
        "the simulator let go of TCP 4560+{}",
        slot.instance()
    );
}

#[test]
fn a_simulator_that_loses_px4_mid_flight_ends_the_flight_link_lost() {
    let tmp = tempfile::tempdir().unwrap();
    let build = fake_iris_build("v1.14.0", "lose:12", &tmp.path().join("pids"));
    let slot = iris_slot();
    let (r, lost, _) = fly_pair(build.path(), slot.instance());
    assert_eq!(r.status, Status::LinkLost, "{:?}", r.reason);
    let lost = lost.expect("the simulator said it lost PX4");
    assert!(lost.contains("link lost") && lost.contains("closed"), "{lost}");
    assert!(port_free(slot.instance()));
}

fn iris_vehicle(build: &Path, instance: u8) -> (tokio::runtime::Runtime, Px4Vehicle) {
    let rt = tokio::runtime::Runtime::new().expect("runtime");
    let settings = Px4Settings {
        boot_timeout: Duration::from_secs(20),
        sim: VehicleSim::Iris,
        mode: FlyMode::Mission,
        ..Px4Settings::new(Px4Build::open(build).expect("a build"), 5.0)
    };
    let v = Px4Vehicle::new(rt.handle().clone(), settings, instance);
    (rt, v)
}

fn pids(path: &Path) -> Vec<i32> {
    std::fs::read_to_string(path)
        .unwrap_or_default()
        .lines()
        .filter_map(|l| l.trim().parse().ok())
        .collect()
}

#[test]
fn a_px4_dying_after_its_boot_is_retried_on_a_fresh_pair_and_not_charged() {
    let tmp = tempfile::tempdir().unwrap();
    let pid_file = tmp.path().join("pids");
    let build = fake_iris_build("v1.14.0", "die", &pid_file);
    let slot = iris_slot();
    let (_rt, mut v) = iris_vehicle(build.path(), slot.instance());
    assert_eq!(v.name(), format!("px4-iris#{}", slot.instance()));
    let csv = tmp.path().join("flights/candidate_0.csv");
    let flown = v.fly(&case(2), &csv, &AtomicBool::new(false)).expect("journaled");
    assert_eq!(flown.status, FlightStatus::BackendFailed, "{:?}", flown.reason);
    let started = pids(&pid_file);
    assert_eq!(started.len(), 2, "a fresh PX4 per attempt");
    for pid in started {
        assert!(gone(pid, Duration::from_secs(5)), "PX4 {pid} outlived its attempt");
    }
    let log = std::fs::read_to_string(tmp.path().join("flights/candidate_0.px4.log")).unwrap();
    assert!(
        log.contains("=== attempt 2") && log.contains("Startup script returned"),
        "{log}"
    );
    assert!(port_free(slot.instance()));
}

#[test]
fn the_simulators_port_taken_is_said_naming_it_and_the_flight_is_not_charged() {
    let tmp = tempfile::tempdir().unwrap();
    let pid_file = tmp.path().join("pids");
    let build = fake_iris_build("v1.14.0", "fly", &pid_file);
    let slot = iris_slot();
    let port = 4560 + u16::from(slot.instance());
    let squatter = std::net::TcpListener::bind(("127.0.0.1", port)).expect("take the port");
    let (_rt, mut v) = iris_vehicle(build.path(), slot.instance());
    let flown = v
        .fly(
            &case(2),
            &tmp.path().join("flights/candidate_0.csv"),
            &AtomicBool::new(false),
        )
        .expect("journaled");
    drop(squatter);
    assert_eq!(flown.status, FlightStatus::BackendFailed);
    let reason = flown.reason.unwrap_or_default();
    assert!(
        reason.contains(&format!("TCP port {port} is in use")) && reason.contains("stop it"),
        "{reason}"
    );
    assert!(pids(&pid_file).is_empty(), "no PX4 started without its simulator");
}

#[test]
fn a_killed_prgenuav_leaves_no_px4_and_frees_the_simulators_port() {
    let tmp = tempfile::tempdir().unwrap();
    let build = fake_iris_build("v1.14.0", "fly", &tmp.path().join("pids"));
    let (_d, test) = test_file(2, valid_pair());
    let mut parent = std::process::Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .args(["fly", test.to_str().unwrap(), "--px4", build.path().to_str().unwrap()])
        .args(["--sim", "iris", "--mode", "mission", "--quiet"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start prgenuav");
    let parent_pid = i32::try_from(parent.id()).unwrap();
    let t0 = Instant::now();
    let (child, instance) = loop {
        let found = children_of(parent_pid)
            .into_iter()
            .find_map(|(pid, _)| Some((pid, instance_of(pid)?)));
        if let Some(found) = found {
            break found;
        }
        assert!(t0.elapsed() < Duration::from_secs(30), "no PX4 within 30 s");
        std::thread::sleep(Duration::from_millis(20));
    };
    // Flying: PX4 connected to the simulator, the simulator serving its port.
    std::thread::sleep(Duration::from_secs(3));
    assert!(!port_free(instance), "the simulator serves TCP 4560+{instance}");
    parent.kill().expect("SIGKILL prgenuav");
    parent.wait().expect("reap prgenuav");
    assert!(
        gone(child, Duration::from_secs(10)),
        "PX4 {child} outlived its killed parent"
    );
    assert!(
        port_free(instance),
        "TCP 4560+{instance} still held after prgenuav died"
    );
}

/// The instance a running fake PX4 serves (from its environment), once it runs as the fake.
fn instance_of(pid: i32) -> Option<u8> {
    let env = std::fs::read(format!("/proc/{pid}/environ")).ok()?;
    let prefix = format!("{FAKE}=");
    env.split(|b| *b == 0)
        .filter_map(|kv| std::str::from_utf8(kv).ok())
        .find_map(|kv| kv.strip_prefix(prefix.as_str())?.parse().ok())
}

#[test]
fn builds_that_cannot_fly_the_iris_or_sih_are_refused_before_anything_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let (_d, test) = test_file(2, valid_pair());
    let t = test.to_str().unwrap();
    let no_module = fake_build_tagged("exit 3", "v1.14.0");
    let v112 = fake_iris_build("v1.12.3", "fly", &tmp.path().join("pids"));
    for (build, sim, says) in [
        (no_module.path(), "iris", "no external-simulator support"),
        (v112.path(), "sih", "has no SIH in SITL"),
    ] {
        let (code, _, err) = super::prgenuav(&["fly", t, "--px4", build.to_str().unwrap(), "--sim", sim]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(says), "{err}");
    }
    let (code, _, err) = super::prgenuav(&["generate", "missions/mission2.yaml", "3", "--sim", "iris"]);
    assert!(code == 2 && err.contains("need --px4"), "{err}");
    assert!(pids(&tmp.path().join("pids")).is_empty());
}
