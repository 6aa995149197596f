//! The simulator against real PX4 SITL (ignored: CI has no PX4). Each test starts the simulator in this
//! process and a PX4 instance as a child, boots it against the simulator, arms, takes off to about 10 m,
//! hovers 10 s of simulated time, lands and waits for PX4 to disarm by itself, judging the flight by the
//! simulator's own ground truth, and prints one line of figures to stderr. The PX4 build is the user's
//! own (`bin/px4` of `build/px4_sitl_default`):
//!
//! ```sh
//! PX4_SITL_BIN=$B14/bin/px4 PX4_SITL_BIN_V116=$B16/bin/px4 PX4_SITL_BIN_V112=$B12/bin/px4 \
//!   cargo test --release -p prgenuav-simulator --test px4_sitl -- --ignored --nocapture --test-threads=1
//! ```

use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use mavlink::dialects::common::{COMMAND_LONG_DATA, HEARTBEAT_DATA, MavCmd, MavMessage, MavModeFlag, MavType};
use mavlink::{AsyncMavConnection, MavHeader};
use simulator::hil::lockstep::LockstepConfig;
use simulator::hil::tcp::SitlServer;
use simulator::{Cancel, SimConfig, Simulator};

/// The PX4 binary in `var`, or a failure naming the variable.
fn bin(var: &str) -> PathBuf {
    match std::env::var_os(var) {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => panic!("this test flies PX4 SITL: set {var}=/path/to/PX4-Autopilot/build/px4_sitl_default/bin/px4"),
    }
}

/// A PX4 instance, killed when dropped (SIGKILL: PX4 ignores SIGTERM while it waits for sensors).
struct Px4 {
    child: Child,
    console: PathBuf,
}

impl Drop for Px4 {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Px4 {
    fn start(bin: &PathBuf, instance: u16, v112: bool) -> Px4 {
        let build = bin
            .parent()
            .and_then(|p| p.parent())
            .expect("BUILD/bin/px4")
            .to_path_buf();
        let dir = std::env::temp_dir().join(format!("prgenuav-sim-px4-{instance}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("work dir");
        let console = dir.join("console.log");
        let out = std::fs::File::create(&console).expect("console");
        let mut cmd = Command::new(bin);
        cmd.env_remove("PX4_SIMULATOR")
            .env("PX4_SIM_MODEL", if v112 { "iris" } else { "none_iris" })
            .args(["-d", "-i", &instance.to_string(), "-w"])
            .arg(&dir);
        if v112 {
            cmd.args(["-s", "etc/init.d-posix/rcS"]);
        }
        let child = cmd
            .arg(build.join("etc"))
            .stdin(Stdio::null())
            .stdout(out.try_clone().expect("clone"))
            .stderr(out)
            .spawn()
            .expect("PX4 starts");
        Px4 { child, console }
    }

    fn console(&self) -> String {
        std::fs::read_to_string(&self.console).unwrap_or_default()
    }
}

fn command(cmd: MavCmd, p: [f32; 7], target: u8) -> MavMessage {
    MavMessage::COMMAND_LONG(COMMAND_LONG_DATA {
        param1: p[0],
        param2: p[1],
        param3: p[2],
        param4: p[3],
        param5: p[4],
        param6: p[5],
        param7: p[6],
        command: cmd,
        target_system: target,
        target_component: 1,
        confirmation: 0,
    })
}

async fn fly(var: &str, instance: u16, v112: bool) {
    let px4_bin = bin(var);
    let addr = format!("127.0.0.1:{}", 4560 + instance).parse().expect("addr");
    let server = SitlServer::bind(addr).await.expect("simulator binds");
    let mut sim = Simulator::new(SimConfig::default());
    let (clock, truth) = (sim.clock(), sim.truth());
    let cancel = Cancel::new();
    let stop = cancel.clone();
    let run = tokio::spawn(async move {
        let r = sim
            .run_sitl(&server, Duration::from_secs(60), &LockstepConfig::default(), &stop)
            .await;
        (r, sim)
    });
    let px4 = Px4::start(&px4_bin, instance, v112);
    let wall = Instant::now();
    let ready = if v112 { "home set" } else { "Ready for takeoff" };
    while !px4.console().contains(ready) {
        assert!(
            wall.elapsed() < Duration::from_secs(90),
            "PX4 not ready:\n{}",
            px4.console()
        );
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    let boot_s = wall.elapsed().as_secs_f64();
    let conn = mavlink::connect_async::<MavMessage>(&format!("udpin:127.0.0.1:{}", 14540 + instance))
        .await
        .expect("udp");
    let gcs = MavHeader {
        system_id: 245,
        component_id: 190,
        sequence: 0,
    };
    let target = (instance + 1) as u8;
    let beat = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_GCS,
        ..HEARTBEAT_DATA::DEFAULT
    });
    // udpin answers the last sender: wait for PX4's first message.
    let _ = tokio::time::timeout(Duration::from_secs(10), conn.recv()).await;
    let send = |m: MavMessage| {
        let c = &conn;
        async move {
            let _ = c.send(&gcs, &m).await;
        }
    };
    send(beat.clone()).await;
    send(command(
        MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        target,
    ))
    .await;
    // Take off to 10 m above the home (param 7: altitude above mean sea level).
    let alt = (SimConfig::default().home.alt_m + 10.0) as f32;
    send(command(
        MavCmd::MAV_CMD_NAV_TAKEOFF,
        [0.0, 0.0, 0.0, f32::NAN, f32::NAN, f32::NAN, alt],
        target,
    ))
    .await;
    // Climb: judged by the ground truth, heartbeats every 0.5 s of wall time.
    let t_takeoff = clock.now();
    let mut peak = 0.0f64;
    loop {
        let z = truth.borrow().position_ned_m.z;
        peak = peak.max(-z);
        if z < -9.0 {
            break;
        }
        assert!(
            clock.now().since(t_takeoff) < Duration::from_secs(60),
            "no climb: at {z} m after {:?} wall\n{}",
            wall.elapsed(),
            px4.console()
        );
        send(beat.clone()).await;
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let climb_s = clock.now().since(t_takeoff).as_secs_f64();
    // Hover 10 s of simulated time after settling 5 s.
    let settle = clock.now();
    while clock.now().since(settle) < Duration::from_secs(5) {
        send(beat.clone()).await;
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let (mut zmin, mut zmax) = (f64::MAX, f64::MIN);
    let hover = clock.now();
    while clock.now().since(hover) < Duration::from_secs(10) {
        let z = -truth.borrow().position_ned_m.z;
        zmin = zmin.min(z);
        zmax = zmax.max(z);
        send(beat.clone()).await;
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    send(command(
        MavCmd::MAV_CMD_NAV_LAND,
        [0.0, 0.0, 0.0, f32::NAN, f32::NAN, f32::NAN, f32::NAN],
        target,
    ))
    .await;
    let land = clock.now();
    let mut disarmed = false;
    while !disarmed {
        assert!(
            clock.now().since(land) < Duration::from_secs(90),
            "did not land and disarm\n{}",
            px4.console()
        );
        send(beat.clone()).await;
        if let Ok(Ok((h, MavMessage::HEARTBEAT(hb)))) =
            tokio::time::timeout(Duration::from_millis(300), conn.recv()).await
            && h.system_id == u32::from(target)
            && !hb.base_mode.contains(MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED)
            && truth.borrow().on_ground
        {
            disarmed = true;
        }
    }
    let land_s = clock.now().since(land).as_secs_f64();
    let rest = *truth.borrow();
    cancel.cancel();
    let (report, _) = run.await.expect("simulator task");
    let report = report.expect("the simulator ran to the cancel");
    let console = px4.console();
    let warnings: Vec<&str> = console
        .lines()
        .filter(|l| {
            let l = l.to_lowercase();
            [
                "preflight fail",
                "stale",
                "high accelerometer bias",
                "yaw estimate",
                "mag ",
                "baro ",
                "ekf2 ",
            ]
            .iter()
            .any(|w| l.contains(w))
                && (l.contains("warn") || l.contains("fail") || l.contains("error"))
        })
        .collect();
    eprintln!(
        "px4_sitl {var}: boot {boot_s:.1} s wall, climb to 9 m {climb_s:.1} s sim, hover {zmin:.3}..{zmax:.3} m, landed+disarmed {land_s:.1} s sim at z {:.3} m, x{:.2} real time, {} steps, {} answers, {} waits timed out, warnings {warnings:?}",
        rest.position_ned_m.z,
        report.real_time_factor(),
        report.lockstep.steps,
        report.lockstep.answers,
        report.lockstep.timeouts
    );
    assert!(zmax - zmin < 0.3, "hover band {zmin}..{zmax}");
    assert_eq!(rest.position_ned_m.z, 0.0);
    assert!(warnings.is_empty(), "{warnings:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4 SITL v1.14 in PX4_SITL_BIN"]
async fn px4_sitl_v114_takes_off_hovers_lands() {
    fly("PX4_SITL_BIN", 8, false).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4 SITL v1.16 in PX4_SITL_BIN_V116"]
async fn px4_sitl_v116_takes_off_hovers_lands() {
    fly("PX4_SITL_BIN_V116", 9, false).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4 SITL v1.12 in PX4_SITL_BIN_V112"]
async fn px4_sitl_v112_takes_off_hovers_lands() {
    fly("PX4_SITL_BIN_V112", 7, true).await;
}
