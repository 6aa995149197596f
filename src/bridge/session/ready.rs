//! Readiness before arming, and arming itself. PX4 arms once its estimator has converged, GPS has a fix and
//! home is set; v1.14 says whether its own arming checks pass for the current mode with the SYS_STATUS health
//! bit MAV_SYS_STATUS_PREARM_CHECK (streams/SYS_STATUS.hpp:146-148; MAVSDK's `health().is_armable` reads the
//! same bit). The bridge waits (bounded) for all of it, then, for a mission, switches to AUTO.MISSION while
//! still disarmed (always allowed disarmed: commander/UserModeIntention.cpp:47): there the bit also covers the
//! navigator's verdict on the mission (modeCheck.cpp:111-123 clears AUTO.MISSION's arming bit without a valid
//! mission). A bit that passes in Hold and fails in AUTO.MISSION means the vehicle refuses this mission, so it
//! is never armed into it.

use std::time::Duration;

use mavlink::dialects::common::{GpsFixType, MavCmd, MavMessage, MavSysStatusSensor};
use tokio::sync::broadcast;

use super::context::{Session, Stop};
use super::report::Status;
use super::schedule::{Action, schedule};
use crate::bridge::options::FlyMode;
use crate::bridge::wire::clock::{VehicleClock, secs};
use crate::bridge::wire::exchange::ProtocolError;
use crate::bridge::wire::notices;
use crate::bridge::wire::notices::{Notice, last_texts, tell, texts_since};
use crate::bridge::wire::vehicle::{PX4_MAIN_AUTO, PX4_SUB_MISSION};

/// PX4 reports a change of its arming checks at most every 2 s (HealthAndArmingChecks/Common.hpp:192), so a
/// SYS_STATUS is only trusted about a mission uploaded this long before it.
pub const REPORT_LAG: Duration = Duration::from_millis(2500);
/// The pre-arm bit failing this long in AUTO.MISSION, while it passed in Hold, is the vehicle refusing the
/// mission.
pub const MISSION_VERDICT: Duration = Duration::from_secs(3);
/// Arming is asked again this often (vehicle time) while the vehicle refuses it...
pub const ARM_RETRY: Duration = Duration::from_secs(1);
/// ...within the readiness budget, but never less than this after the first attempt.
pub const ARM_MIN_BUDGET: Duration = Duration::from_secs(10);
/// Waiting notices go out this often (vehicle time), or when what is missing changes.
const NOTICE_EVERY: Duration = Duration::from_secs(5);

/// What the vehicle has told about its readiness, folded from its messages.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReadyState {
    /// HOME_POSITION received.
    pub home: bool,
    /// GPS_RAW_INT fix type, if streamed.
    pub gps_fix: Option<GpsFixType>,
    /// SYS_STATUS (enabled, health) and when it arrived (vehicle time).
    pub sys_status: Option<(MavSysStatusSensor, MavSysStatusSensor, Duration)>,
    /// PX4 (main, sub) mode from the autopilot's HEARTBEAT.
    pub px4_mode: (u8, u8),
}

impl ReadyState {
    /// Folds one message in at vehicle time `now`.
    pub fn update(&mut self, msg: &MavMessage, now: Duration) {
        match msg {
            MavMessage::HOME_POSITION(_) => self.home = true,
            MavMessage::GPS_RAW_INT(g) => self.gps_fix = Some(g.fix_type),
            MavMessage::SYS_STATUS(s) => {
                self.sys_status = Some((s.onboard_control_sensors_enabled, s.onboard_control_sensors_health, now));
            }
            MavMessage::HEARTBEAT(h)
                if h.autopilot != mavlink::dialects::common::MavAutopilot::MAV_AUTOPILOT_INVALID =>
            {
                self.px4_mode = (((h.custom_mode >> 16) & 0xFF) as u8, (h.custom_mode >> 24) as u8);
            }
            _ => {}
        }
    }

    /// The pre-arm bit of the last SYS_STATUS.
    pub fn prearm(&self) -> Option<bool> {
        self.sys_status
            .map(|(_, h, _)| h.contains(MavSysStatusSensor::MAV_SYS_STATUS_PREARM_CHECK))
    }

    /// Enabled sensors the vehicle calls unhealthy (pre-arm bit aside).
    pub fn unhealthy(&self) -> MavSysStatusSensor {
        self.sys_status.map_or(MavSysStatusSensor::empty(), |(e, h, _)| {
            (e - h) - MavSysStatusSensor::MAV_SYS_STATUS_PREARM_CHECK
        })
    }

    /// What is still missing before arming, in words (empty: ready).
    pub fn missing(&self) -> Vec<&'static str> {
        use MavSysStatusSensor as S;
        let mut out = Vec::new();
        if !self.home {
            out.push("home position");
        }
        if self
            .gps_fix
            .is_some_and(|f| (f as u8) < GpsFixType::GPS_FIX_TYPE_3D_FIX as u8)
        {
            out.push("GPS 3D fix");
        }
        let bad = self.unhealthy();
        if bad.contains(S::MAV_SYS_STATUS_AHRS) {
            out.push("estimator converged (AHRS)");
        }
        if bad.contains(S::MAV_SYS_STATUS_SENSOR_GPS) {
            out.push("GPS healthy");
        }
        match self.prearm() {
            None => out.push("SYS_STATUS"),
            Some(false) => out.push("PX4's pre-arm checks"),
            Some(true) => {}
        }
        out
    }
}

/// The flight starts with the mission (first action Start, not offboard): switch to AUTO.MISSION first.
pub fn starts_mission(s: &Session<'_>) -> bool {
    matches!(s.opts.mode, FlyMode::Avoidance | FlyMode::Mission)
        && schedule(&s.test.commands, &mut Vec::new())
            .front()
            .is_some_and(|(_, a)| *a == Action::Start)
}

enum Verdict {
    Ready,
    Wait,
    Refused,
}

/// Waits (bounded by `ready_timeout_s`) until the vehicle is ready to arm, telling the user what is missing;
/// a mission the vehicle refuses ends the flight here, unarmed.
pub async fn wait_ready(s: &mut Session<'_>, st: &mut ReadyState) -> Result<(), Stop> {
    let clock = s.link.clock();
    let start = s.ready.started.unwrap_or_else(|| clock.now());
    let budget_s = s.opts.ready_budget_s(clock.scale());
    let deadline = start + secs(budget_s);
    s.ready.deadline = deadline;
    let mission = starts_mission(s);
    // (switch time, health at the switch) once in AUTO.MISSION on our request.
    let mut switched: Option<(Duration, MavSysStatusSensor)> = None;
    let mut told: Option<(Duration, Vec<&'static str>)> = None;
    let first_message = notices::count(&s.messages);
    let mut home_asked = false;
    loop {
        let now = clock.now();
        let missing = st.missing();
        if !home_asked && !st.home && now >= start + Duration::from_secs(1) {
            // Ask once; a vehicle without home yet refuses, and the stream brings it later.
            home_asked = true;
            let _ = s
                .command(MavCmd::MAV_CMD_REQUEST_MESSAGE, [242.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
                .await;
            continue;
        }
        if missing.is_empty() {
            match (mission, switched) {
                (false, _) => break,
                (true, None) => {
                    switched = Some((now, st.unhealthy()));
                    if st.px4_mode != (PX4_MAIN_AUTO, PX4_SUB_MISSION) && !switch_to_mission(s).await? {
                        break;
                    }
                    continue;
                }
                (true, Some(_)) => {}
            }
        }
        if let Some((at, health)) = switched {
            match mission_verdict(st, at, health, s.ready.mission_uploaded_at, now) {
                Verdict::Ready => break,
                Verdict::Refused => return Err(mission_refused(s, first_message)),
                Verdict::Wait => {}
            }
        }
        if now >= deadline {
            return Err(not_ready(s, budget_s, &missing));
        }
        tell_waiting(s, &mut told, missing, (start, now));
        let wait = clock.wall_until(deadline).min(clock.wall(Duration::from_millis(200)));
        next_message(s, st, &clock, wait).await?;
    }
    s.ready.waited_s = Some(clock.now().saturating_sub(start).as_secs_f64());
    Ok(())
}

/// Tells the user what the vehicle still lacks, waited for since `start`, when that changed or
/// [`NOTICE_EVERY`] passed since it was last told (`told`: when, and what).
fn tell_waiting(
    s: &Session<'_>,
    told: &mut Option<(Duration, Vec<&'static str>)>,
    missing: Vec<&'static str>,
    (start, now): (Duration, Duration),
) {
    let stale = told
        .as_ref()
        .is_none_or(|(t, m)| *m != missing || now >= *t + NOTICE_EVERY);
    if missing.is_empty() || !stale {
        return;
    }
    tell(
        s.opts.notices.as_ref(),
        &Notice::Waiting {
            missing: missing.join(", "),
            waited_s: now.saturating_sub(start).as_secs_f64(),
        },
    );
    *told = Some((now, missing));
}

/// Switches to AUTO.MISSION while disarmed, so the pre-arm bit covers the mission. False: the switch failed
/// (warned), and arming goes ahead without the vehicle's verdict on the mission.
async fn switch_to_mission(s: &mut Session<'_>) -> Result<bool, Stop> {
    let mode = [
        1.0,
        f32::from(PX4_MAIN_AUTO),
        f32::from(PX4_SUB_MISSION),
        0.0,
        0.0,
        0.0,
        0.0,
    ];
    match s.command(MavCmd::MAV_CMD_DO_SET_MODE, mode).await {
        Ok(()) => Ok(true),
        Err(ProtocolError::Cancelled) => Err(Stop::new(Status::Aborted, "cancelled while waiting for the vehicle")),
        Err(e) => {
            s.warnings.push(format!("switching to AUTO.MISSION before arming: {e}"));
            Ok(false)
        }
    }
}

/// The stop for a mission the vehicle refuses, quoting what it said since the wait began.
fn mission_refused(s: &Session<'_>, first_message: usize) -> Stop {
    let said = texts_since(&s.messages, first_message)
        .or_else(|| last_texts(&s.messages, 3))
        .unwrap_or_else(|| "no reason given".into());
    Stop::new(
        Status::Rejected,
        format!(
            "the vehicle refuses this mission (its pre-arm check passes in Hold but fails in AUTO.MISSION): {said}"
        ),
    )
}

/// The stop for a vehicle not ready within the budget, with what is still missing.
fn not_ready(s: &Session<'_>, budget_s: f64, missing: &[&str]) -> Stop {
    let said = last_texts(&s.messages, 3).unwrap_or_else(|| "no reason given".into());
    Stop::new(
        Status::Rejected,
        format!(
            "not ready to arm within {budget_s:.0} s (missing: {}); vehicle: {said}",
            if missing.is_empty() {
                "PX4's pre-arm checks in AUTO.MISSION".into()
            } else {
                missing.join(", ")
            }
        ),
    )
}

/// Folds in the next message, or returns after `wait` (wall time) without one; Ctrl-C aborts.
async fn next_message(
    s: &mut Session<'_>,
    st: &mut ReadyState,
    clock: &VehicleClock,
    wait: Duration,
) -> Result<(), Stop> {
    tokio::select! {
        biased;
        _ = s.cancel.cancelled() => return Err(Stop::new(Status::Aborted, "cancelled while waiting for the vehicle")),
        r = s.rx.recv() => match r {
            Ok(inb) => {
                let t = clock.now();
                st.update(&inb.msg, t);
                s.view.update(&inb.msg, t);
            }
            Err(broadcast::error::RecvError::Lagged(_)) => {}
            Err(broadcast::error::RecvError::Closed) => tokio::time::sleep(wait).await,
        },
        _ = tokio::time::sleep(wait) => {}
    }
    Ok(())
}

/// The mission verdict from a SYS_STATUS in AUTO.MISSION: trusted once it postdates the switch and the
/// mission upload by PX4's reporting lag; a refusal needs the sensors as healthy as at the switch.
fn mission_verdict(
    st: &ReadyState,
    switched_at: Duration,
    health_at_switch: MavSysStatusSensor,
    uploaded_at: Option<Duration>,
    now: Duration,
) -> Verdict {
    let Some((_, _, at)) = st.sys_status else {
        return Verdict::Wait;
    };
    let trusted_from = switched_at.max(uploaded_at.map_or(Duration::ZERO, |u| u + REPORT_LAG));
    if at <= trusted_from || st.px4_mode != (PX4_MAIN_AUTO, PX4_SUB_MISSION) {
        return Verdict::Wait;
    }
    match st.prearm() {
        Some(true) if st.missing().is_empty() => Verdict::Ready,
        Some(false) if st.unhealthy() == health_at_switch && now >= trusted_from + MISSION_VERDICT => Verdict::Refused,
        _ => Verdict::Wait,
    }
}

/// Arms, asking again every [`ARM_RETRY`] while the vehicle refuses (a still-settling estimator), within the
/// readiness budget; the final refusal quotes the vehicle.
pub async fn arm(s: &mut Session<'_>) -> Result<(), Stop> {
    let clock = s.link.clock();
    let deadline = s.ready.deadline.max(clock.now() + ARM_MIN_BUDGET);
    let first_message = notices::count(&s.messages);
    let arm = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    loop {
        let e = match s.command(MavCmd::MAV_CMD_COMPONENT_ARM_DISARM, arm).await {
            Ok(()) => return Ok(()),
            Err(e @ ProtocolError::CommandRefused { .. }) if clock.now() + ARM_RETRY < deadline => e,
            Err(e) => {
                let mut stop = super::context::stop_for("arming", e);
                if stop.status == Status::Rejected
                    && let Some(said) = texts_since(&s.messages, first_message).or_else(|| last_texts(&s.messages, 3))
                {
                    stop.reason = format!("{}; vehicle: {said}", stop.reason);
                }
                return Err(stop);
            }
        };
        s.warnings.push(format!("arming refused, asking again: {e}"));
        tokio::select! {
            _ = s.cancel.cancelled() => return Err(Stop::new(Status::Aborted, "cancelled while arming")),
            _ = tokio::time::sleep(clock.wall(ARM_RETRY)) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mavlink::dialects::common::{GPS_RAW_INT_DATA, SYS_STATUS_DATA};

    fn sys(health: MavSysStatusSensor) -> MavMessage {
        use MavSysStatusSensor as S;
        MavMessage::SYS_STATUS(SYS_STATUS_DATA {
            onboard_control_sensors_enabled: S::MAV_SYS_STATUS_AHRS | S::MAV_SYS_STATUS_SENSOR_GPS,
            onboard_control_sensors_health: health,
            ..Default::default()
        })
    }

    #[test]
    fn readiness_lists_what_is_missing() {
        use MavSysStatusSensor as S;
        let mut st = ReadyState::default();
        assert_eq!(st.missing(), vec!["home position", "SYS_STATUS"]);
        st.update(&sys(S::MAV_SYS_STATUS_SENSOR_GPS), Duration::ZERO);
        let gps = MavMessage::GPS_RAW_INT(GPS_RAW_INT_DATA {
            fix_type: GpsFixType::GPS_FIX_TYPE_2D_FIX,
            ..Default::default()
        });
        st.update(&gps, Duration::ZERO);
        assert_eq!(
            st.missing(),
            vec![
                "home position",
                "GPS 3D fix",
                "estimator converged (AHRS)",
                "PX4's pre-arm checks"
            ]
        );
        st.update(&MavMessage::HOME_POSITION(Default::default()), Duration::ZERO);
        let gps = MavMessage::GPS_RAW_INT(GPS_RAW_INT_DATA {
            fix_type: GpsFixType::GPS_FIX_TYPE_RTK_FIXED,
            ..Default::default()
        });
        st.update(&gps, Duration::ZERO);
        let all = S::MAV_SYS_STATUS_AHRS | S::MAV_SYS_STATUS_SENSOR_GPS | S::MAV_SYS_STATUS_PREARM_CHECK;
        st.update(&sys(all), Duration::ZERO);
        assert!(st.missing().is_empty(), "{:?}", st.missing());
    }

    #[test]
    fn mission_verdict_waits_for_px4s_report_then_decides() {
        use MavSysStatusSensor as S;
        let healthy = S::MAV_SYS_STATUS_AHRS | S::MAV_SYS_STATUS_SENSOR_GPS;
        let mut st = ReadyState {
            home: true,
            px4_mode: (PX4_MAIN_AUTO, PX4_SUB_MISSION),
            ..Default::default()
        };
        let s = Duration::from_secs;
        let up = Some(s(10));
        st.update(&sys(healthy), s(11));
        assert!(
            matches!(mission_verdict(&st, s(11), S::empty(), up, s(11)), Verdict::Wait),
            "too early"
        );
        st.update(&sys(healthy), s(13));
        assert!(
            matches!(mission_verdict(&st, s(11), S::empty(), up, s(13)), Verdict::Wait),
            "not for 3 s yet"
        );
        st.update(&sys(healthy), s(16));
        assert!(matches!(
            mission_verdict(&st, s(11), S::empty(), up, s(16)),
            Verdict::Refused
        ));
        // The estimator went bad meanwhile: not the mission's fault, keep waiting.
        st.update(&sys(S::MAV_SYS_STATUS_SENSOR_GPS), s(16));
        assert!(matches!(
            mission_verdict(&st, s(11), S::empty(), up, s(16)),
            Verdict::Wait
        ));
        st.update(&sys(healthy | S::MAV_SYS_STATUS_PREARM_CHECK), s(13));
        assert!(matches!(
            mission_verdict(&st, s(11), S::empty(), up, s(13)),
            Verdict::Ready
        ));
        st.px4_mode = (4, 3);
        assert!(
            matches!(mission_verdict(&st, s(11), S::empty(), up, s(13)), Verdict::Wait),
            "not in mission"
        );
    }
}
