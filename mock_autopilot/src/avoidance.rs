//! PX4 <= 1.14's obstacle-avoidance interface (COM_OBS_AVOID = 1).
//!
//! The vehicle streams TRAJECTORY_REPRESENTATION_WAYPOINTS at 5 Hz (point 0: the setpoint it
//! would fly, 1: current waypoint, 2: next waypoint), follows the companion's point 0, and holds
//! position when no valid answer came for 0.5 s. The companion (component 196) must heartbeat.

use std::time::Duration;

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
use mavlink::dialects::common::{MavMessage, MavSeverity, MavState, TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA};

use crate::dynamics::{Ned, Setpoint};

/// Trajectory stream period (5 Hz).
pub const SEND_PERIOD: Duration = Duration::from_millis(200);
/// An answer older than this is stale: hold position.
pub const ANSWER_TIMEOUT: Duration = Duration::from_millis(500);
/// Without a companion heartbeat for this long the avoidance system counts as lost.
pub const HEARTBEAT_TIMEOUT: Duration = Duration::from_secs(5);

/// What the companion's point 0 asks for, by which of its components are finite (local NED).
///
/// PX4 copies point 0's position and velocity over its own setpoint (ObstacleAvoidance.cpp
/// `injectAvoidanceSetpoints`, release/1.14 l. 116-119), and its trajectory generator then treats a finite
/// position axis as a target and a NaN one as "follow the velocity" (PositionSmoothing.cpp
/// `_generateVelocitySetpoint`, l. 170-257).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Target {
    /// Position (x, y, z): fly there (a velocity alongside is a feed-forward the mock ignores).
    Position(Ned),
    /// Position (x, y, NaN) with velocity z: hold x, y and climb or descend at that rate (PX4's own land
    /// setpoint has this shape).
    XyPositionZVelocity((f64, f64), f64),
    /// Position NaN, velocity (vx, vy, vz).
    Velocity(Ned),
}

/// Companion setpoint from point 0.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Answer {
    target: Target,
    yaw: Option<f64>,
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
    /// Vertical speed caps (up, down), m/s, of PX4's auto modes (MPC_Z_V_AUTO_UP/DN; the mock's
    /// MPC_Z_VEL_MAX_UP/DN), for a companion's position during landing.
    z_caps_m_s: Option<(f64, f64)>,
}

fn finite3(x: f32, y: f32, z: f32) -> Option<Ned> {
    (x.is_finite() && y.is_finite() && z.is_finite()).then(|| Ned::new(x.into(), y.into(), z.into()))
}

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
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
        let pos = finite3(t.pos_x[0], t.pos_y[0], t.pos_z[0]);
        let vel = finite3(t.vel_x[0], t.vel_y[0], t.vel_z[0]);
        let xy_vz = (t.pos_x[0].is_finite() && t.pos_y[0].is_finite() && t.vel_z[0].is_finite())
            .then(|| ((f64::from(t.pos_x[0]), f64::from(t.pos_y[0])), f64::from(t.vel_z[0])));
        let target = match (pos, xy_vz, vel) {
            (Some(p), _, _) => Target::Position(p),
            (None, Some((xy, vz)), _) => Target::XyPositionZVelocity(xy, vz),
            (None, None, Some(v)) => Target::Velocity(v),
            // Nothing PX4's controller could track on every axis.
            (None, None, None) => return,
        };
        let yaw = t.pos_yaw[0].is_finite().then(|| f64::from(t.pos_yaw[0]));
        self.answer = Some(Answer { target, yaw, at: now });
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

    /// The auto modes' vertical speed caps (up, down), m/s, positive.
    pub fn set_z_caps(&mut self, up_m_s: f64, down_m_s: f64) {
        self.z_caps_m_s = Some((up_m_s, down_m_s));
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
        let sp = match fresh {
            Some(a) => answer_setpoint(&a, &nav_sp, self.z_caps_m_s),
            None => {
                if now.saturating_sub(self.answer.map_or(since, |a| a.at.max(since))) > ANSWER_TIMEOUT
                    && !self.timeout_reported
                {
                    self.timeout_reported = true;
                    texts.push((MavSeverity::MAV_SEVERITY_CRITICAL, "Avoidance system timeout".into()));
                }
                // PX4 holds the position where the answers stopped, also at the ground, where that is no
                // commanded descent, so it never lands (ObstacleAvoidance.cpp l. 96-104).
                Setpoint::Position {
                    target_ned: *self.hold.get_or_insert(pos),
                    h_speed_m_s: 1.0,
                    up_speed_m_s: 1.0,
                    down_speed_m_s: 1.0,
                    yaw_rad: None,
                }
            }
        };
        (sp, msg)
    }
}

/// The speed caps (horizontal, up, down; m/s) PX4 keeps applying whatever the companion sends: the
/// navigator's own, e.g. MPC_TKO_SPEED during takeoff (FlightTaskAuto.cpp `_updateTrajConstraints`, l. 819-843,
/// chooses them from PX4's waypoint type, not from the injected setpoint); while landing the auto modes'
/// vertical caps `z_caps` (the land speed is only PX4's own velocity setpoint).
fn caps(nav_sp: &Setpoint, z_caps: Option<(f64, f64)>) -> (f64, f64, f64) {
    match *nav_sp {
        Setpoint::Position {
            h_speed_m_s,
            up_speed_m_s,
            down_speed_m_s,
            ..
        } => (h_speed_m_s, up_speed_m_s, down_speed_m_s),
        Setpoint::XyPositionZVelocity {
            h_speed_m_s, vel_z_m_s, ..
        } => {
            let (up, down) = z_caps.unwrap_or((vel_z_m_s.abs(), vel_z_m_s.abs()));
            (h_speed_m_s, up, down)
        }
        Setpoint::Velocity { .. } | Setpoint::Idle => (5.0, 1.0, 1.0),
    }
}

/// The setpoint to fly for a fresh answer, within the navigator's caps (`nav_sp`).
fn answer_setpoint(a: &Answer, nav_sp: &Setpoint, z_caps: Option<(f64, f64)>) -> Setpoint {
    let (h_speed_m_s, up_speed_m_s, down_speed_m_s) = caps(nav_sp, z_caps);
    let vz = |vz: f64| vz.clamp(-up_speed_m_s, down_speed_m_s);
    match a.target {
        Target::Position(target_ned) => Setpoint::Position {
            target_ned,
            h_speed_m_s,
            up_speed_m_s,
            down_speed_m_s,
            yaw_rad: a.yaw,
        },
        Target::XyPositionZVelocity(target_xy_ned, vel_z_m_s) => Setpoint::XyPositionZVelocity {
            target_xy_ned,
            h_speed_m_s,
            vel_z_m_s: vz(vel_z_m_s),
            yaw_rad: a.yaw,
        },
        Target::Velocity(v) => Setpoint::Velocity {
            vel_ned: Ned::new(v.x, v.y, vz(v.z)),
            yaw_rad: a.yaw,
        },
    }
}

/// PX4 1.14's request: point 0 is the auto flight task's own setpoint with its type as `command[0]`
/// (FlightTaskAuto.cpp `updateAvoidanceDesiredSetpoints(_position_setpoint, _velocity_setpoint, _type)`); while
/// landing that is the land point's x, y with z unset and the descent speed as z velocity
/// (`_prepareLandSetpoints`). Points 1 and 2 are the current and next mission item.
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
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
            target_ned, yaw_rad, ..
        } => {
            set_point(&mut t, 0, target_ned);
            t.pos_yaw[0] = yaw_rad.map_or(f32::NAN, |y| y as f32);
        }
        Setpoint::XyPositionZVelocity {
            target_xy_ned: (n, e),
            vel_z_m_s,
            yaw_rad,
            ..
        } => {
            // PX4's land setpoint as it asks the companion: position (x, y, NaN), velocity (NaN, NaN, vz).
            t.pos_x[0] = n as f32;
            t.pos_y[0] = e as f32;
            t.vel_z[0] = vel_z_m_s as f32;
            t.pos_yaw[0] = yaw_rad.map_or(f32::NAN, |y| y as f32);
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

#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
fn set_point(t: &mut TRAJECTORY_REPRESENTATION_WAYPOINTS_DATA, i: usize, p: Ned) {
    t.pos_x[i] = p.x as f32;
    t.pos_y[i] = p.y as f32;
    t.pos_z[i] = p.z as f32;
}

#[cfg(test)]
#[expect(deprecated, reason = "PX4 <= 1.15's avoidance interface, deprecated upstream")]
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
    fn silence_at_the_ground_holds_position_and_land_answers_keep_their_shape() {
        let mut a = Avoidance::default();
        let mut texts = vec![];
        let land = Setpoint::XyPositionZVelocity {
            target_xy_ned: (2.0, 3.0),
            h_speed_m_s: 5.0,
            vel_z_m_s: 0.7,
            yaw_rad: None,
        };
        let ground = Ned::new(2.0, 3.0, 0.0);
        let (_, m) = a.apply(Duration::ZERO, land, ground, (u16::MAX, [None, None]), 0, &mut texts);
        let Some(MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(req)) = m else {
            panic!("request expected")
        };
        // PX4's land setpoint as the companion sees it.
        assert_eq!((req.pos_x[0], req.pos_y[0], req.vel_z[0]), (2.0, 3.0, 0.7));
        assert!(req.pos_z[0].is_nan() && req.vel_x[0].is_nan() && req.vel_y[0].is_nan());
        // No answer: hold where the answers stopped, even on the ground (not idle: that would land).
        let (s, _) = a.apply(
            Duration::from_secs(1),
            land,
            ground,
            (u16::MAX, [None, None]),
            0,
            &mut texts,
        );
        assert!(
            matches!(s, Setpoint::Position { target_ned, .. } if target_ned == ground),
            "{s:?}"
        );
        // Its mirror flies PX4's land setpoint, within the auto modes' vertical caps.
        let mut answer = req.clone();
        answer.valid_points = 1;
        answer.vel_z[0] = 9.0;
        a.set_z_caps(3.0, 1.5);
        a.on_trajectory(Duration::from_millis(1100), &answer);
        let (s, _) = a.apply(
            Duration::from_millis(1200),
            land,
            ground,
            (u16::MAX, [None, None]),
            0,
            &mut texts,
        );
        assert!(
            matches!(s, Setpoint::XyPositionZVelocity { target_xy_ned: (2.0, 3.0), vel_z_m_s, .. } if vel_z_m_s == 1.5),
            "{s:?}"
        );
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
