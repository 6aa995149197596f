//! A flight controller in the loop (`--hitl`) without one: the mock autopilot behind a serial cable of
//! pseudo-terminals stands in for the board (a board in HITL takes the simulator's sensors; the mock flies
//! its own model and ignores them). Checked: the flight goes through the simulator's UDP gateway and lands,
//! a board not in HITL mode is refused before anything is set or armed naming SYS_HITL 1, airframe 1001 and
//! pwm_out_sim, a board that falls silent mid-flight ends it `link_lost` with the simulator saying so, and a
//! serial device that goes away ends the simulator naming it.

use std::io::Write;
use std::time::Duration;

use mavlink::MavHeader;
use mavlink::dialects::common::{HEARTBEAT_DATA, MavAutopilot, MavMessage, MavType};
use mock_autopilot::{LinkSpec, MockAutopilot, MockHandle, SpeedFactor};
use prgenuav::bridge::hil::board::{Board, BoardPort};
use prgenuav::bridge::{CancelToken, FlightReport, FlyMode, FlyOptions, Status, fly};

use super::pty::{SerialCable, lone_pty};
use super::{case, valid_pair};

/// The stand-in board's clock: faster than the wall clock a real board keeps, so the test is short.
const SPEED: f64 = 10.0;

async fn stand_in(cable: &SerialCable, sys_hitl: i32) -> MockHandle {
    MockAutopilot::builder()
        .link(LinkSpec::Address(format!("serial:{}:921600", cable.b)))
        .speed_factor(SpeedFactor::Times(SPEED))
        .param("SYS_HITL", mock_autopilot::params::ParamValue::Int(sys_hitl))
        .spawn()
        .await
        .expect("the stand-in board")
}

async fn board_on(cable: &SerialCable) -> Board {
    let port = BoardPort::parse(&format!("serial:{}:921600", cable.a)).expect("a port");
    Board::start(&port, case(2).home, 3)
        .await
        .expect("the simulator on the board's port")
}

fn opts(board: &Board) -> FlyOptions {
    FlyOptions {
        connect: board.url().to_string(),
        mode: FlyMode::Mission,
        time_scale: SPEED,
        heartbeat_wait_s: 60.0,
        require_hitl: true,
        ..FlyOptions::default()
    }
}

async fn fly_board(board: &Board, cancel: CancelToken) -> FlightReport {
    let test = case(2).with_obstacles(valid_pair());
    tokio::time::timeout(Duration::from_secs(180), fly(&test, &opts(board), cancel))
        .await
        .expect("the flight ends in time")
        .expect("the flight runs")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_board_in_hitl_mode_flies_through_the_simulators_gateway() {
    let cable = SerialCable::new().expect("pseudo-terminals");
    let mock = stand_in(&cable, 1).await;
    let board = board_on(&cable).await;
    let r = fly_board(&board, CancelToken::new()).await;
    mock.shutdown().await.expect("stops");
    let summary = board.stop().await;
    assert!(r.status.completed(), "{:?} {:?}", r.status, r.reason);
    assert!(r.min_distance.is_some() && r.samples > 100);
    assert_eq!(summary.link, "serial wall clock");
    assert!(summary.steps > 1000 && summary.error.is_none(), "{summary}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_board_not_in_hitl_mode_is_refused_before_anything_is_set() {
    let cable = SerialCable::new().expect("pseudo-terminals");
    let mock = stand_in(&cable, 0).await;
    let board = board_on(&cable).await;
    let r = fly_board(&board, CancelToken::new()).await;
    mock.shutdown().await.expect("stops");
    board.stop().await;
    assert_eq!(r.status, Status::Rejected);
    let reason = r.reason.unwrap_or_default();
    for part in [
        "SYS_HITL is 0",
        "SYS_HITL 1",
        "airframe 1001",
        "pwm_out_sim",
        "nothing was set or armed",
    ] {
        assert!(reason.contains(part), "{part}: {reason}");
    }
    assert_eq!((r.samples, r.fence_uploaded), (0, false), "nothing uploaded or flown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_board_falling_silent_mid_flight_ends_it_link_lost() {
    let cable = SerialCable::new().expect("pseudo-terminals");
    let mock = stand_in(&cable, 1).await;
    let board = board_on(&cable).await;
    let flight = fly_board(&board, CancelToken::new());
    let unplug = async {
        // Setup takes about 3 s of wall time (the clock is measured over 1.5 s), the flight some 8 s.
        tokio::time::sleep(Duration::from_secs(5)).await;
        mock.shutdown().await.expect("stops");
    };
    let (r, ()) = tokio::join!(flight, unplug);
    assert_eq!(r.status, Status::LinkLost, "{:?}", r.reason);
    let why = failure_within(&board, Duration::from_secs(10)).await;
    // Silent, or no longer reading what the simulator writes: either way the link is gone.
    assert!(why.contains("link lost"), "{why}");
    board.stop().await;
}

/// What the board's simulator ended with, waiting for it at most `wait`.
async fn failure_within(board: &Board, wait: Duration) -> String {
    let t0 = std::time::Instant::now();
    loop {
        if let Some(why) = board.failure() {
            return why;
        }
        assert!(t0.elapsed() < wait, "the simulator did not notice within {wait:?}");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test]
async fn a_serial_device_that_goes_away_ends_the_simulator_naming_it() {
    let (mut master, path) = lone_pty().expect("a pty");
    let port = BoardPort::parse(&format!("serial:{path}:921600")).expect("a port");
    let board = Board::start(&port, case(2).home, 0)
        .await
        .expect("the simulator on the pty");
    // The board speaks once, then its USB device is unplugged.
    let hb = MavMessage::HEARTBEAT(HEARTBEAT_DATA {
        mavtype: MavType::MAV_TYPE_QUADROTOR,
        autopilot: MavAutopilot::MAV_AUTOPILOT_PX4,
        ..HEARTBEAT_DATA::DEFAULT
    });
    let mut frame = Vec::new();
    mavlink::write_v2_msg(&mut frame, MavHeader::default(), &hb).expect("frame");
    master.write_all(&frame).expect("write");
    tokio::time::sleep(Duration::from_millis(300)).await;
    drop(master);
    let why = failure_within(&board, Duration::from_secs(10)).await;
    assert!(why.contains("link lost"), "{why}");
    let summary = board.stop().await;
    assert!(summary.error.is_some());
}
