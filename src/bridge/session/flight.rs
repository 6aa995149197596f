//! Following the flight: run the test's commands at their times (mode 3 = arm and start), record every
//! position, and end on landing, timeout, Ctrl-C, silence or reboot; on an abnormal end command LAND (RTL if
//! LAND is refused), keeping the recording.

use std::time::Duration;

use mavlink::dialects::common::{MavCmd, MavMessage};
use tokio::sync::{broadcast, watch};

use super::context::{Session, Stop, stop_for};
use super::recorder::Recorder;
use super::report::Status;
use super::schedule::{Action, schedule};
use crate::bridge::companion::cp_feed::CpProgress;
use crate::bridge::companion::frame::{FramedSteer, TestFrame};
use crate::bridge::companion::offboard::{self, Pilot, PilotProgress};
use crate::bridge::companion::planner_steer::PlannerSteer;
use crate::bridge::companion::steer::{MirrorSetpoint, Steer, Straight};
use crate::bridge::options::FlyMode;
use crate::bridge::options::{FlyMode as Mode, FlyOptions};
use crate::bridge::wire::cancel::CancelToken;
use crate::bridge::wire::clock::{VehicleClock, secs};
use crate::bridge::wire::command::AckedCommand;
use crate::bridge::wire::exchange::RetryPolicy;
use crate::bridge::wire::vehicle::{PX4_MAIN_OFFBOARD, VehicleView};
use crate::lfs::camera::Camera;
use crate::model::TestCase;

/// How often the end conditions are checked when nothing arrives (vehicle time).
const TICK: Duration = Duration::from_millis(100);

/// The steering for `opts.mode`: the LFS planner over the test's boxes, planning in the test's frame and
/// answering in the vehicle's (`frame`; `None` = the two coincide); if it cannot be built, the interface's
/// fallbacks (mirror PX4's setpoint; fly straight in offboard).
pub fn steer_for(
    test: &TestCase,
    opts: &FlyOptions,
    frame: Option<TestFrame>,
    mpc_xy_cruise_m_s: Option<f64>,
) -> Box<dyn Steer> {
    let steer = PlannerSteer::with_cruise(&test.obstacles, Camera::hfs(), mpc_xy_cruise_m_s)
        .map(|s| s.with_style(opts.companion));
    let planned: Box<dyn Steer> = match (steer, opts.mode) {
        (Ok(p), Mode::Avoidance | Mode::Offboard) => Box::new(p),
        (_, Mode::Avoidance) => return Box::new(MirrorSetpoint),
        _ => Box::new(Straight),
    };
    match frame {
        Some(f) => Box::new(FramedSteer::new(f, planned)),
        None => planned,
    }
}

/// In lockstep, silence shorter than this (wall time) is the vehicle waiting for the companion.
const LOCKSTEP_SILENCE: Duration = Duration::from_secs(2);
/// A lost link is also this much wall time of silence: a simulator K times faster than real time stalls in wall
/// time when its machine is busy (PX4 SIH at speed factor 5 on a loaded 2-core machine went 1 s without a word,
/// which is 5 s of its time), and such a stall is not a lost link.
const MIN_WALL_SILENCE: Duration = Duration::from_secs(3);

/// Whether `silence` (vehicle time since the vehicle was last heard) means the link is lost: longer than `loss`
/// in vehicle time and than [`MIN_WALL_SILENCE`] in wall time; in lockstep (the vehicle silent while it waits
/// for our answer) only wall-time silence beyond [`LOCKSTEP_SILENCE`] counts at all.
fn link_lost(silence: Option<Duration>, loss: Duration, clock: &VehicleClock, lockstep: bool) -> bool {
    silence.is_some_and(|d| {
        let wall = clock.wall(d);
        (!lockstep || wall > LOCKSTEP_SILENCE) && d > loss && wall >= MIN_WALL_SILENCE
    })
}

/// Vehicle time since the flight started. In lockstep the scaled wall clock runs ahead of the vehicle, so the
/// vehicle's own `time_boot_ms` counts, bounded by real time (never slower than 1x) so a flight always ends.
fn flight_time(s: &Session<'_>, clock: &VehicleClock, start: Duration, now: Duration, boot0: Option<u32>) -> Duration {
    let scaled = now.saturating_sub(start);
    if s.opts.lockstep.is_none() {
        return scaled;
    }
    let reported = match (boot0, s.view.pose) {
        (Some(b0), Some(p)) => Duration::from_millis(u64::from(p.time_boot_ms.saturating_sub(b0))),
        _ => Duration::ZERO,
    };
    reported.max(clock.wall(scaled))
}

/// What [`follow`] keeps between its rounds to judge whether the flight has ended.
struct Ends {
    /// Vehicle time the flight started.
    start: Duration,
    /// The test's time limit.
    timeout: Duration,
    /// Silence (vehicle time) that means a lost link.
    loss: Duration,
    /// The vehicle has been seen armed.
    was_armed: bool,
    /// The vehicle's `time_boot_ms` at the start, once a position brought it.
    start_boot_ms: Option<u32>,
}

/// Follows the flight to its end.
pub async fn follow(s: &mut Session<'_>, rec: &mut Recorder) -> Stop {
    let clock = s.link.clock();
    s.drain();
    let start = clock.now();
    // Setup took its time; silence is measured from here.
    s.view.last_heard = Some(start);
    let mut ends = Ends {
        start,
        timeout: secs(s.opts.timeout_s),
        loss: secs(s.opts.link_loss_s),
        was_armed: false,
        start_boot_ms: s.view.pose.map(|p| p.time_boot_ms),
    };
    let mut plan = schedule(&s.test.commands, &mut s.warnings);
    let mut progress = (s.opts.mode == FlyMode::Offboard).then(|| start_pilot(s));
    let mut cp = (s.opts.mode == FlyMode::CollisionPrevention).then(|| s.start_cp_feed());
    let mut landing_sent = false;
    let mut cp_mode_try = None;
    loop {
        let now = clock.now();
        while plan.front().is_some_and(|(at, _)| start + *at <= now) {
            let Some((_, action)) = plan.pop_front() else { break };
            if let Err(stop) = execute(s, action, progress.as_mut(), cp.as_mut()).await {
                return end(s, stop).await;
            }
        }
        if let Some(stop) = ends.check(s, rec, &clock, now).await {
            return stop;
        }
        let pilots = (progress.as_ref(), cp.as_ref());
        let finished = match pilot_news(s, rec, pilots, landing_sent, &mut cp_mode_try).await {
            Ok(f) => f,
            Err(stop) => return stop,
        };
        if !landing_sent && finished {
            landing_sent = true;
            if let Err(e) = s
                .command(
                    MavCmd::MAV_CMD_NAV_LAND,
                    [0.0, 0.0, 0.0, f32::NAN, f32::NAN, f32::NAN, f32::NAN],
                )
                .await
            {
                return end(s, stop_for("landing after the last waypoint", e)).await;
            }
        }
        tokio::select! {
            biased;
            _ = s.cancel.cancelled() => return end(s, Stop::new(Status::Aborted, "cancelled (Ctrl-C)")).await,
            r = s.rx.recv() => match r {
                Ok(inb) => {
                    take(s, rec, &inb.msg, clock.now());
                }
                Err(broadcast::error::RecvError::Lagged(n)) => s.warnings.push(format!("{n} messages lost (slow consumer)")),
                Err(broadcast::error::RecvError::Closed) => tokio::time::sleep(clock.wall(TICK)).await,
            },
            _ = tokio::time::sleep(clock.wall(TICK)) => {}
        }
    }
}

/// Whether the pilot (offboard or Collision Prevention) reached every waypoint. A Collision Prevention pilot
/// that gave up ends the flight as a timeout (landing it); a failsafe that took its vehicle out of Position
/// mode is undone.
async fn pilot_news(
    s: &mut Session<'_>,
    rec: &mut Recorder,
    pilots: (
        Option<&watch::Receiver<PilotProgress>>,
        Option<&watch::Receiver<CpProgress>>,
    ),
    landing_sent: bool,
    mode_try: &mut Option<Duration>,
) -> Result<bool, Stop> {
    let cp = match pilots {
        (_, Some(cp)) => cp,
        (offboard, None) => return Ok(offboard.is_some_and(|p| p.borrow().finished)),
    };
    let (stuck, finished, streaming) = {
        let c = cp.borrow();
        (c.stuck.clone(), c.finished, c.streaming)
    };
    if let Some(why) = stuck {
        let stop = end(s, Stop::new(Status::Timeout, why)).await;
        see_it_land(s, rec).await;
        return Err(stop);
    }
    if streaming && !landing_sent && !finished {
        s.keep_position_mode(mode_try).await;
    }
    Ok(finished)
}

/// Starts the offboard pilot over the mission's goals; its progress says when to switch modes and land.
fn start_pilot(s: &mut Session<'_>) -> watch::Receiver<PilotProgress> {
    let acc = s
        .test
        .params
        .iter()
        .find(|p| p.name == "NAV_ACC_RAD")
        .map_or(1.0, |p| p.value.clamp(0.5, 1.0));
    // The mission's goals are in the test's frame; the pilot flies in the vehicle's.
    let goals = offboard::goals(&s.test.mission);
    let goals = match s.frame {
        Some(f) => goals.into_iter().map(|g| f.to_vehicle(g)).collect(),
        None => goals,
    };
    let pilot = Pilot::new(goals, acc);
    let steer = steer_for(s.test, s.opts, s.frame, s.mpc_xy_cruise_m_s);
    let (task, rx) = offboard::spawn(s.link.clone(), s.target, pilot, steer);
    s.tasks.push(task);
    rx
}

impl Ends {
    /// How the flight ended at vehicle time `now`, if it has: reboot, silence, landing, a disarm before
    /// takeoff or the time limit. An abnormal end has been answered with LAND already.
    async fn check(
        &mut self,
        s: &mut Session<'_>,
        rec: &mut Recorder,
        clock: &VehicleClock,
        now: Duration,
    ) -> Option<Stop> {
        self.was_armed |= s.view.armed;
        self.start_boot_ms = self.start_boot_ms.or(s.view.pose.map(|p| p.time_boot_ms));
        if s.view.rebooted {
            return Some(end(s, Stop::new(Status::LinkLost, "the autopilot rebooted mid-flight")).await);
        }
        if link_lost(s.view.silent_for(now), self.loss, clock, s.opts.lockstep.is_some()) {
            let why = format!(
                "no message from the vehicle for {:.1} s (and at least {} s of wall time)",
                self.loss.as_secs_f64(),
                MIN_WALL_SILENCE.as_secs()
            );
            return Some(end(s, Stop::new(Status::LinkLost, why)).await);
        }
        if s.view.landed_after_flight() {
            return Some(Stop::new(Status::Landed, "landed and disarmed"));
        }
        if self.was_armed && !s.view.armed && !s.view.took_off {
            let why = s
                .view
                .warnings
                .last()
                .cloned()
                .unwrap_or_else(|| "no reason given".into());
            return Some(Stop::new(
                Status::Rejected,
                format!("the vehicle disarmed before taking off: {why}"),
            ));
        }
        if flight_time(s, clock, self.start, now, self.start_boot_ms) > self.timeout {
            let why = format!("still flying after {} s", s.opts.timeout_s);
            let stop = end(s, Stop::new(Status::Timeout, why)).await;
            see_it_land(s, rec).await;
            return Some(stop);
        }
        None
    }
}

async fn execute(
    s: &mut Session<'_>,
    action: Action,
    progress: Option<&mut watch::Receiver<PilotProgress>>,
    cp: Option<&mut watch::Receiver<CpProgress>>,
) -> Result<(), Stop> {
    if let (Action::Start, Some(cp)) = (&action, cp) {
        return s.start_position_mode(cp).await;
    }
    let nan = f32::NAN;
    match (action, s.opts.mode) {
        (Action::Start, FlyMode::Offboard) => {
            if let Some(p) = progress {
                let wait = s.link.clock().wall(Duration::from_secs(5));
                if tokio::time::timeout(wait, p.wait_for(|p| p.streaming)).await.is_err() {
                    return Err(Stop::new(
                        Status::LinkLost,
                        "no position from the vehicle to start offboard from",
                    ));
                }
            }
            let mode = [1.0, f32::from(PX4_MAIN_OFFBOARD), 0.0, 0.0, 0.0, 0.0, 0.0];
            s.command(MavCmd::MAV_CMD_DO_SET_MODE, mode)
                .await
                .map_err(|e| stop_for("switching to OFFBOARD", e))?;
            super::ready::arm(s).await
        }
        (Action::Start, _) => {
            if super::held_start::start_at_a_hold(s).await {
                return Ok(());
            }
            super::ready::arm(s).await?;
            let last = s.test.mission.items.len().saturating_sub(1) as f32;
            s.command(MavCmd::MAV_CMD_MISSION_START, [0.0, last, 0.0, 0.0, 0.0, 0.0, 0.0])
                .await
                .map_err(|e| stop_for("starting the mission", e))
        }
        (Action::Takeoff, _) => s
            .command(MavCmd::MAV_CMD_NAV_TAKEOFF, [nan, 0.0, 0.0, nan, nan, nan, nan])
            .await
            .map_err(|e| stop_for("takeoff", e)),
        (Action::Land, _) => s
            .command(MavCmd::MAV_CMD_NAV_LAND, [0.0, 0.0, 0.0, nan, nan, nan, nan])
            .await
            .map_err(|e| stop_for("land", e)),
        (Action::Arm, _) => super::ready::arm(s).await,
        (Action::Disarm, _) => s
            .command(
                MavCmd::MAV_CMD_COMPONENT_ARM_DISARM,
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            )
            .await
            .map_err(|e| stop_for("disarming", e)),
    }
}

/// Ends an abnormal flight: LAND (then RTL if LAND is refused) unless the vehicle is on the ground, bounded
/// and not cancellable (the user's Ctrl-C is what brought us here).
async fn end(s: &mut Session<'_>, stop: Stop) -> Stop {
    s.drain();
    if !needs_landing(&s.view, stop.status) {
        return stop;
    }
    let quick = RetryPolicy {
        timeout: Duration::from_millis(1000),
        max_retries: 2,
    };
    let uncancellable = CancelToken::new();
    let nan = f32::NAN;
    for cmd in [MavCmd::MAV_CMD_NAV_LAND, MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH] {
        let c = AckedCommand::new(s.target, cmd, [0.0, 0.0, 0.0, nan, nan, nan, nan], quick);
        match s.link.exchange(c, &uncancellable).await {
            Ok(()) => {
                s.warnings.push(format!("{cmd:?} sent after {}", stop.status.as_str()));
                return stop;
            }
            Err(e) => s.warnings.push(format!("{cmd:?} failed: {e}")),
        }
    }
    stop
}

/// Folds a message into the view and records a new position, in the test's frame where the obstacles are.
fn take(s: &mut Session<'_>, rec: &mut Recorder, msg: &MavMessage, now: Duration) {
    s.view.update(msg, now);
    if let (MavMessage::LOCAL_POSITION_NED(_), Some(p)) = (msg, s.view.pose)
        && !s.view.rebooted
    {
        rec.push(&s.frame.map_or(p, |f| f.pose_to_test(&p)));
    }
}

/// How long (vehicle time) to follow a vehicle landing after a timeout: from the arena's 25 m ceiling at
/// PX4's slowest default descent (0.7 m/s) with margin.
const SETTLE_AFTER_LAND: Duration = Duration::from_secs(60);

/// After LAND at a timeout: keep recording until the vehicle has landed and disarmed (bounded), so the next
/// flight on this vehicle starts on the ground and the report says whether the LAND took effect.
async fn see_it_land(s: &mut Session<'_>, rec: &mut Recorder) {
    let clock = s.link.clock();
    let start = clock.now();
    let boot0 = s.view.pose.map(|p| p.time_boot_ms);
    while s.view.armed && !s.view.landed_after_flight() {
        let elapsed = flight_time(s, &clock, start, clock.now(), boot0);
        let wait = clock
            .wall(SETTLE_AFTER_LAND.saturating_sub(elapsed))
            .min(clock.wall(TICK));
        if elapsed >= SETTLE_AFTER_LAND {
            s.warnings
                .push(format!("still armed {} s after LAND", SETTLE_AFTER_LAND.as_secs()));
            return;
        }
        match tokio::time::timeout(wait, s.rx.recv()).await {
            Ok(Ok(inb)) => {
                take(s, rec, &inb.msg, clock.now());
            }
            Ok(Err(broadcast::error::RecvError::Lagged(_))) => {}
            Err(_) => {} // a tick without news: the deadline is checked above
            Ok(Err(broadcast::error::RecvError::Closed)) => {
                s.warnings.push("lost the vehicle while it landed after LAND".into());
                return;
            }
        }
    }
    s.warnings.push("landed and disarmed after LAND".into());
}

fn needs_landing(view: &VehicleView, status: Status) -> bool {
    match status {
        Status::Timeout | Status::Aborted | Status::LinkLost => view.armed || view.took_off,
        _ => view.armed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lost_link_is_silence_in_vehicle_and_wall_time() {
        let loss = Duration::from_secs(5);
        let s = Duration::from_secs_f64;
        // A real vehicle (1x): 5 s of silence.
        let real = VehicleClock::new(1.0);
        assert!(!link_lost(Some(s(4.9)), loss, &real, false));
        assert!(link_lost(Some(s(5.1)), loss, &real, false));
        assert!(!link_lost(None, loss, &real, false));
        // SITL at 5x: 6 s of its time is 1.2 s of wall time, a stall of a busy machine, not a lost link.
        let sitl = VehicleClock::new(5.0);
        assert!(!link_lost(Some(s(6.0)), loss, &sitl, false));
        assert!(link_lost(Some(s(15.5)), loss, &sitl, false));
        // Lockstep: the vehicle waits for us; only wall-time silence beyond LOCKSTEP_SILENCE counts.
        let fast = VehicleClock::new(100.0);
        assert!(!link_lost(Some(s(150.0)), loss, &fast, true), "1.5 s of wall time");
        assert!(link_lost(Some(s(350.0)), loss, &fast, true), "3.5 s of wall time");
    }
}
