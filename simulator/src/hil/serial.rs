//! A board in the loop (HITL) over a serial port, on the wall clock at 250 Hz: sensors stamped with the
//! wall clock (a board ignores `time_usec`, PX4 SITL behind a pty follows it), HEARTBEATs at 1 Hz so PX4
//! on USB enables MAVLink, never HIL_STATE_QUATERNION (a board takes it as its own state), and the board's
//! other traffic through the [`Gateway`].

use std::time::{Duration, Instant};

use tokio::io::{AsyncRead, AsyncWrite};
use tokio::time::MissedTickBehavior;
use tokio_serial::SerialPortBuilderExt;

use super::gateway::Gateway;
use super::link::{Frame, LinkEvent, Outbox, spawn_reader};
use super::messages::{Incoming, classify, is_hil};
use super::stepper::{Observers, Stamp, StepCounts, Stepper};
use crate::cancel::Cancel;
use crate::error::SimError;
use crate::sim::Simulation;
use crate::time::STEP;

/// Opens `device` at `baud` (8N1, no flow control).
pub fn open(device: &str, baud: u32) -> Result<tokio_serial::SerialStream, SimError> {
    tokio_serial::new(device, baud)
        .timeout(Duration::from_millis(100))
        .open_native_async()
        .map_err(|e| SimError::SerialOpen {
            device: device.to_string(),
            baud,
            source: e,
        })
}

/// The wall-clock run's figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallClockConfig {
    /// Silence from the board (once heard) after which the link counts as lost.
    pub link_lost_after: Duration,
    /// The board must be heard within this of opening the port.
    pub first_heard_within: Duration,
}

impl Default for WallClockConfig {
    fn default() -> Self {
        Self {
            link_lost_after: Duration::from_secs(3),
            first_heard_within: Duration::from_secs(120),
        }
    }
}

/// What a wall-clock run did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WallClockReport {
    /// Steps taken.
    pub steps: u64,
    /// Ticks the wall clock skipped because a step came late.
    pub late_ticks: u64,
    /// Motor commands received.
    pub answers: u64,
    /// Step counters.
    pub counts: StepCounts,
    /// Frames forwarded to the gateway's endpoint.
    pub to_endpoint: u64,
    /// Datagrams passed to the board.
    pub to_board: u64,
    /// Wall seconds run.
    pub wall_s: f64,
}

struct Run {
    stepper: Stepper,
    out: Outbox,
    report: WallClockReport,
    heard: Option<Instant>,
}

/// Runs the board's loop on `port` until cancelled or the link fails; the report covers it either way.
pub async fn run_wall_clock<P>(
    port: P,
    sim: &mut Simulation,
    obs: &mut Observers,
    mut gateway: Option<Gateway>,
    config: &WallClockConfig,
    cancel: &Cancel,
) -> (WallClockReport, Result<(), SimError>)
where
    P: AsyncRead + AsyncWrite + Send + 'static,
{
    let (read, mut write) = tokio::io::split(port);
    let (mut rx, reader) = spawn_reader(read);
    let t0 = Instant::now();
    let mut tick = tokio::time::interval(STEP);
    tick.set_missed_tick_behavior(MissedTickBehavior::Skip);
    let mut run = Run {
        stepper: Stepper::new(false, 0),
        out: Outbox::default(),
        report: WallClockReport::default(),
        heard: None,
    };
    let mut buf = vec![0u8; 65_536];
    let mut last_tick = Instant::now();
    let result = loop {
        if let Err(e) = check_silence(&run, t0, config) {
            break Err(e);
        }
        tokio::select! {
            _ = tick.tick() => {
                let now = Instant::now();
                if now.duration_since(last_tick) > STEP * 2 {
                    run.report.late_ticks += 1;
                }
                last_tick = now;
                run.stepper.step(sim, &mut run.out, obs, Stamp::WallSince(t0)).await;
                run.report.steps += 1;
            }
            ev = rx.recv() => match ev {
                Some(LinkEvent::Frame(f)) => on_frame(&mut run, sim, gateway.as_mut(), *f),
                Some(LinkEvent::Closed(why)) => break Err(SimError::LinkLost(format!("serial device closed or unplugged ({why})"))),
                None => break Err(SimError::LinkLost("serial reader stopped".into())),
            },
            n = recv_gateway(gateway.as_mut(), &mut buf) => {
                if let Some(n) = n {
                    run.out.push_raw(&buf[..n]);
                }
            }
            _ = cancel.cancelled() => break Ok(()),
        }
        if let Err(e) = run.out.flush(&mut write, config.link_lost_after).await {
            break Err(SimError::LinkLost(format!("serial device: {e}")));
        }
    };
    reader.abort();
    let mut report = run.report;
    report.counts = run.stepper.counts();
    report.wall_s = t0.elapsed().as_secs_f64();
    if let Some(g) = &gateway {
        report.to_endpoint = g.to_endpoint;
        report.to_board = g.to_board;
    }
    (report, result)
}

fn check_silence(run: &Run, t0: Instant, config: &WallClockConfig) -> Result<(), SimError> {
    match run.heard {
        Some(t) if t.elapsed() >= config.link_lost_after => Err(SimError::LinkLost(format!(
            "the board fell silent for {:?}",
            config.link_lost_after
        ))),
        None if t0.elapsed() >= config.first_heard_within => Err(SimError::NeverAnswered(config.first_heard_within)),
        _ => Ok(()),
    }
}

fn on_frame(run: &mut Run, sim: &mut Simulation, gateway: Option<&mut Gateway>, f: Frame) {
    run.heard = Some(Instant::now());
    if let Some(m) = &f.message {
        let incoming = classify(m);
        if matches!(incoming, Incoming::Actuators { .. }) {
            run.report.answers += 1;
        }
        run.stepper.on_incoming(sim, &incoming);
    }
    if !is_hil(f.message_id)
        && let Some(g) = gateway
    {
        g.forward(&f.bytes);
    }
}

/// A datagram from the gateway, or never when there is none.
async fn recv_gateway(gateway: Option<&mut Gateway>, buf: &mut [u8]) -> Option<usize> {
    match gateway {
        Some(g) => g.recv(buf).await.ok(),
        None => std::future::pending().await,
    }
}
