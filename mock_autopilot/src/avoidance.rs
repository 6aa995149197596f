//! PX4 <= 1.14's obstacle-avoidance interface (COM_OBS_AVOID = 1).
//!
//! The vehicle streams TRAJECTORY_REPRESENTATION_WAYPOINTS at 5 Hz (point 0: the setpoint it
//! would fly, 1: current waypoint, 2: next waypoint), follows the companion's point 0, and holds
//! position when no valid answer came for 0.5 s. The companion (component 196) must heartbeat.
#![allow(deprecated)] // TRAJECTORY_REPRESENTATION_WAYPOINTS is deprecated upstream (PX4 1.15 removed it).

use std::time::Duration;

use mavlink::dialects::common::{MavMessage, MavSeverity, MavState, TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA};

use crate::dynamics::{Ned, Setpoint};

/// Trajectory stream period (5 Hz).
pub const SEND_PERIOD: Duration = Duration::from_millis(200);
/// An answer older than this is stale: hold position.
pub const ANSWER_TIMEOUT: Duration = Duration::from_millis(500);
/// Without a companion heartbeat for this long the avoidance system counts as lost.
pub const HEARTBEAT_TIMEOUT: Duration = Duration::from_secs(5);
const LAND: u16 = mavlink::dialects::common::MavCmd::MAV_CMD_NAV_LAND as u16;

/// Companion setpoint from point 0 (local NED).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Answer {
    pos: Option<Ned>,
    vel: Option<Ned>,
    yaw: Option<f64>,
    /// Descent speed of a land answer (z unset, z velocity set), m/s down.
    descend: Option<f64>,
    at: Duration,
}

/// State of the avoidance interface.
#[derive(Debug, Clone, Default)]
pub struct Avoidance {
    heartbeat: Option<(Duration, bool)>,
    answer: Option<Answer>,
    next_send: Duration,
    waiting_since: Option<Duration>,
    hold: Option<Ned>,
    timeout_reported: bool,
    lost_reported: bool,
    /// A request went out and no valid answer came since (lockstep waits on this).
    awaiting: bool,
}

fn finite3(x: f32, y: f32, z: f32) -> Option<Ned> {
    (x.is_finite() && y.is_finite() && z.is_finite()).then(|| Ned::new(x.into(), y.into(), z.into()))
}

impl Avoidance {
    /// A HEARTBEAT from component 196.
    pub fn on_heartbeat(&mut self, now: Duration, status: MavState) {
        self.heartbeat = Some((now, status == MavState::MAV_STATE_ACTIVE));
        self.lost_reported = false;
    }

    /// A TRAJECTORY_REPRESENTATION_WAYPOINTS from the companion; invalid ones are ignored.
    pub fn on_trajectory(&mut self, now: Duration, t: &TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA) {
        if t.valid_points == 0 {
            return;
        }
        let mut pos = finite3(t.pos_x[0], t.pos_y[0], t.pos_z[0]);
        let vel = finite3(t.vel_x[0], t.vel_y[0], t.vel_z[0]);
        // PX4's own kind of land setpoint (x, y held, z unset, descent speed; FlightTaskAuto.cpp
        // _prepareLandSetpoints), as PX4-Avoidance answers while landing: the mock's descent model aims below
        // the ground at that speed, as its navigator does for its own landing.
        let mut descend = None;
        if pos.is_none() && t.pos_x[0].is_finite() && t.pos_y[0].is_finite() && t.vel_z[0].is_finite() {
            pos = Some(Ned::new(t.pos_x[0].into(), t.pos_y[0].into(), 1.0));
            descend = Some(f64::from(t.vel_z[0]).max(0.1));
        }
        if pos.is_none() && vel.is_none() {
            return;
        }
        let yaw = t.pos_yaw[0].is_finite().then(|| f64::from(t.pos_yaw[0]));
        self.answer = Some(Answer {
            pos,
            vel,
            yaw,
            descend,
            at: now,
        });
        self.awaiting = false;
        self.timeout_reported = false;
        self.hold = None;
    }

    /// Companion heartbeat seen recently with status ACTIVE (arming check).
    pub fn is_healthy(&self, now: Duration) -> bool {
        matches!(self.heartbeat, Some((t, true)) if now.saturating_sub(t) <= HEARTBEAT_TIMEOUT)
    }

    /// Forget the current episode (on disarm or when leaving auto modes). The next request goes out at
    /// once, so the request schedule is in phase with the mode switch (repeatable lockstep flights).
    pub fn reset(&mut self) {
        self.waiting_since = None;
        self.hold = None;
        self.timeout_reported = false;
        self.awaiting = false;
        self.next_send = Duration::ZERO;
    }

    /// True while the latest request is unanswered and the companion is alive: a lockstep simulation holds
    /// its clock here (as PX4 SITL waits for its simulator), so the plan is never late in vehicle time.
    pub fn awaiting_answer(&self, now: Duration) -> bool {
        self.awaiting && self.is_healthy(now)
    }

    /// Stop waiting for the latest request's answer (the lockstep wait timed out).
    pub fn release(&mut self) {
        self.awaiting = false;
    }

    /// The setpoint to fly instead of `nav_sp`, plus texts and the message to send (5 Hz).
    pub fn apply(
        &mut self,
        now: Duration,
        nav_sp: Setpoint,
        pos: Ned,
        (sp_command, waypoints): (u16, [Option<(Ned, u16)>; 2]),
        time_usec: u64,
        texts: &mut Vec<(MavSeverity, String)>,
    ) -> (Setpoint, Option<MavMessage>) {
        // Idle on the ground there is nothing to avoid: no request, so a companion's state (and a lockstep
        // flight) does not depend on how long the vehicle sat armed before the mission started.
        let msg = (now >= self.next_send && nav_sp != Setpoint::Idle).then(|| {
            self.next_send = now + SEND_PERIOD;
            self.awaiting = true;
            MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(request(&nav_sp, sp_command, waypoints, time_usec))
        });
        if self.heartbeat.is_some() && !self.is_healthy(now) && !self.lost_reported {
            self.lost_reported = true;
            texts.push((MavSeverity::MAV_SEVERITY_CRITICAL, "Avoidance system lost".into()));
        }
        if nav_sp == Setpoint::Idle {
            return (nav_sp, msg);
        }
        let since = *self.waiting_since.get_or_insert(now);
        let fresh = self
            .answer
            .filter(|a| a.at >= since && now.saturating_sub(a.at) <= ANSWER_TIMEOUT);
        let sp = match (fresh, nav_sp) {
            (
                Some(a),
                Setpoint::Position {
                    h_speed_m_s,
                    up_speed_m_s,
                    down_speed_m_s,
                    ..
                },
            ) if a.pos.is_some() => Setpoint::Position {
                target_ned: a.pos.unwrap_or(pos),
                h_speed_m_s,
                up_speed_m_s,
                down_speed_m_s: a.descend.unwrap_or(down_speed_m_s),
                yaw_rad: a.yaw,
            },
            (Some(a), _) if a.vel.is_some() => Setpoint::Velocity {
                vel_ned: a.vel.unwrap_or_default(),
                yaw_rad: a.yaw,
            },
            (Some(a), other) => match a.pos {
                Some(p) => Setpoint::Position {
                    target_ned: p,
                    h_speed_m_s: 5.0,
                    up_speed_m_s: 1.0,
                    down_speed_m_s: 1.0,
                    yaw_rad: a.yaw,
                },
                None => other,
            },
            (None, _) => {
                if now.saturating_sub(self.answer.map_or(since, |a| a.at.max(since))) > ANSWER_TIMEOUT
                    && !self.timeout_reported
                {
                    self.timeout_reported = true;
                    texts.push((MavSeverity::MAV_SEVERITY_CRITICAL, "Avoidance system timeout".into()));
                }
                let h = *self.hold.get_or_insert(pos);
                if h.z >= -0.05 {
                    Setpoint::Idle
                } else {
                    Setpoint::Position {
                        target_ned: h,
                        h_speed_m_s: 1.0,
                        up_speed_m_s: 1.0,
                        down_speed_m_s: 1.0,
                        yaw_rad: None,
                    }
                }
            }
        };
        (sp, msg)
    }
}

/// PX4 1.14's request: point 0 is the auto flight task's own setpoint with its type as `command[0]`
/// (FlightTaskAuto.cpp `updateAvoidanceDesiredSetpoints(_position_setpoint, _velocity_setpoint, _type)`); while
/// landing that is the land point's x, y with z unset and the descent speed as z velocity
/// (`_prepareLandSetpoints`). Points 1 and 2 are the current and next mission item.
fn request(
    nav_sp: &Setpoint,
    sp_command: u16,
    waypoints: [Option<(Ned, u16)>; 2],
    time_usec: u64,
) -> TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
    let nan = [f32::NAN; 5];
    let mut t = TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
        time_usec,
        pos_x: nan,
        pos_y: nan,
        pos_z: nan,
        vel_x: nan,
        vel_y: nan,
        vel_z: nan,
        acc_x: nan,
        acc_y: nan,
        acc_z: nan,
        pos_yaw: nan,
        vel_yaw: nan,
        command: [u16::MAX; 5],
        valid_points: 3,
    };
    match *nav_sp {
        Setpoint::Position {
            target_ned,
            yaw_rad,
            down_speed_m_s,
            ..
        } => {
            set_point(&mut t, 0, target_ned);
            t.pos_yaw[0] = yaw_rad.map_or(f32::NAN, |y| y as f32);
            if sp_command == LAND {
                t.pos_z[0] = f32::NAN;
                t.vel_z[0] = down_speed_m_s as f32;
            }
        }
        Setpoint::Velocity { vel_ned, .. } => {
            t.vel_x[0] = vel_ned.x as f32;
            t.vel_y[0] = vel_ned.y as f32;
            t.vel_z[0] = vel_ned.z as f32;
        }
        Setpoint::Idle => {}
    }
    t.command[0] = sp_command;
    for (i, wp) in waypoints.iter().enumerate() {
        if let Some((p, cmd)) = wp {
            set_point(&mut t, i + 1, *p);
            t.command[i + 1] = *cmd;
        }
    }
    t
}

fn set_point(t: &mut TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA, i: usize, p: Ned) {
    t.pos_x[i] = p.x as f32;
    t.pos_y[i] = p.y as f32;
    t.pos_z[i] = p.z as f32;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sp(target: Ned) -> Setpoint {
        Setpoint::Position {
            target_ned: target,
            h_speed_m_s: 5.0,
            up_speed_m_s: 1.5,
            down_speed_m_s: 1.0,
            yaw_rad: None,
        }
    }

    fn answer(p: Ned) -> TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA {
        let mut t = request(&sp(p), u16::MAX, [None, None], 0);
        t.valid_points = 1;
        t
    }

    #[test]
    fn follows_answers_and_holds_after_timeout() {
        let mut a = Avoidance::default();
        let mut texts = vec![];
        let air = Ned::new(0.0, 0.0, -10.0);
        let ms = Duration::from_millis;
        let (s, m) = a.apply(
            ms(0),
            sp(Ned::new(50.0, 0.0, -10.0)),
            air,
            (u16::MAX, [None, None]),
            0,
            &mut texts,
        );
        assert!(m.is_some(), "first request goes out at once");
        assert!(
            matches!(s, Setpoint::Position { target_ned, .. } if target_ned == air),
            "no answer yet: hold"
        );
        let (_, m) = a.apply(
            ms(100),
            sp(Ned::new(50.0, 0.0, -10.0)),
            air,
            (u16::MAX, [None, None]),
            0,
            &mut texts,
        );
        assert!(m.is_none(), "5 Hz");
        a.on_trajectory(ms(150), &answer(Ned::new(3.0, 1.0, -10.0)));
        let (s, m) = a.apply(
            ms(200),
            sp(Ned::new(50.0, 0.0, -10.0)),
            air,
            (u16::MAX, [None, None]),
            0,
            &mut texts,
        );
        assert!(m.is_some());
        assert!(matches!(s, Setpoint::Position { target_ned, .. } if target_ned == Ned::new(3.0, 1.0, -10.0)));
        assert!(texts.is_empty());
        let (s, _) = a.apply(
            ms(700),
            sp(Ned::new(50.0, 0.0, -10.0)),
            Ned::new(1.0, 0.0, -10.0),
            (u16::MAX, [None, None]),
            0,
            &mut texts,
        );
        assert!(matches!(s, Setpoint::Position { target_ned, .. } if target_ned == Ned::new(1.0, 0.0, -10.0)));
        assert_eq!(texts.len(), 1);
        assert!(texts[0].1.contains("timeout"));
    }

    #[test]
    fn invalid_answers_are_ignored_and_health_needs_active_heartbeat() {
        let mut a = Avoidance::default();
        let mut t = answer(Ned::new(1.0, 1.0, -1.0));
        t.valid_points = 0;
        a.on_trajectory(Duration::ZERO, &t);
        assert!(a.answer.is_none());
        let mut t = request(&Setpoint::Idle, u16::MAX, [None, None], 0);
        t.valid_points = 1;
        a.on_trajectory(Duration::ZERO, &t);
        assert!(a.answer.is_none());
        assert!(!a.is_healthy(Duration::ZERO));
        a.on_heartbeat(Duration::ZERO, MavState::MAV_STATE_STANDBY);
        assert!(!a.is_healthy(Duration::ZERO));
        a.on_heartbeat(Duration::ZERO, MavState::MAV_STATE_ACTIVE);
        assert!(a.is_healthy(Duration::from_secs(1)));
        assert!(!a.is_healthy(Duration::from_secs(6)));
    }
}
