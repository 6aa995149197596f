//! `prgenuav-sim` standalone, as someone who starts PX4 themselves runs it (like jMAVSim): it waits for PX4
//! instance N on TCP 4560+N, feeds it sensors in lockstep, stops cleanly on Ctrl-C (exit 0), and refuses a
//! taken port naming it (exit 2). A fake PX4 on a loopback TCP client stands in for PX4 SITL.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use mavlink::dialects::common::MavMessage;
use mavlink::{AsyncMavlinkReader, MavHeader};
use simulator::hil::messages::actuator_controls;
use tokio::net::TcpStream;

/// The instance the tests serve (port 4567), unlikely to be in use by a PX4 instance of a campaign.
const INSTANCE: u16 = 7;

fn start(extra: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_prgenuav-sim"))
        .args(["--instance", &INSTANCE.to_string(), "--connect-timeout-s", "20"])
        .args(extra)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("prgenuav-sim starts")
}

/// PX4's side: connects as PX4 instance [`INSTANCE`] does, retrying until the simulator listens.
async fn connect_as_px4() -> TcpStream {
    let t0 = Instant::now();
    loop {
        match TcpStream::connect(("127.0.0.1", 4560 + INSTANCE)).await {
            Ok(s) => return s,
            Err(e) if t0.elapsed() > Duration::from_secs(20) => panic!("prgenuav-sim never listened: {e}"),
            Err(_) => tokio::time::sleep(Duration::from_millis(50)).await,
        }
    }
}

fn stderr_of(child: Child) -> (i32, String) {
    let out = child.wait_with_output().expect("exits");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Sends `signal` to `child` (then [`stderr_of`] waits for it).
fn signal(child: &Child, signal: &str) {
    let pid = child.id().to_string();
    let sent = Command::new("kill").args([signal, &pid]).status().expect("kill runs");
    assert!(sent.success());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn prgenuav_sim_serves_a_px4_instance_in_lockstep_and_stops_on_ctrl_c() {
    if std::net::TcpListener::bind(("127.0.0.1", 4560 + INSTANCE)).is_err() {
        return; // another simulator serves instance 7 on this machine: nothing to learn here
    }
    let sim = start(&["--speed", "0", "--seed", "3"]);
    let (read, mut write) = connect_as_px4().await.into_split();
    let mut reader = AsyncMavlinkReader::new(read);
    let header = MavHeader {
        system_id: 1,
        component_id: 1,
        sequence: 0,
    };
    let mut last = 0;
    let mut steps = 0;
    let deadline = Instant::now() + Duration::from_secs(20);
    while steps < 500 {
        assert!(Instant::now() < deadline, "only {steps} steps");
        let (_, msg) = reader.read_any_message::<MavMessage>().await.expect("a message");
        if let MavMessage::HIL_SENSOR(s) = msg {
            assert!(s.time_usec > last, "sensor time moves forward");
            last = s.time_usec;
            steps += 1;
            let answer = actuator_controls(s.time_usec, &[0.0; 4], false);
            mavlink::write_v2_msg_async(&mut write, header, &answer)
                .await
                .expect("answer");
        }
    }
    // A second simulator for the same instance is refused, naming the port and the fix.
    let (code, err) = stderr_of(start(&[]));
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("TCP port 4567 is in use") && err.contains("stop it"),
        "{err}"
    );
    signal(&sim, "-INT");
    let (code, err) = stderr_of(sim);
    assert_eq!(code, 0, "Ctrl-C is a clean stop: {err}");
    assert!(
        err.contains("waiting for PX4 instance 7") && err.contains("stopped:"),
        "{err}"
    );
}

#[test]
fn bad_input_is_refused_with_exit_2() {
    for (args, says) in [
        (vec!["--home", "91,8,488"], "out of range"),
        (vec!["--serial", "/dev/ttyACM0"], "DEVICE:BAUD"),
        (vec!["--serial", "/dev/prgenuav-no-such-board:921600"], "plugged in"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_prgenuav-sim"))
            .args(&args)
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
}
