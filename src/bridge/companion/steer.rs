//! Where to fly next around the virtual obstacles: the one question both the avoidance companion and the
//! offboard pilot ask. Implemented by the LFS planner ([`super::planner_steer`]) and, without obstacles to
//! avoid, by flying straight at the goal.

/// PX4's navigation state as the planner's waypoint generator needs it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Nav {
    /// AUTO.MISSION.
    Mission,
    /// AUTO.TAKEOFF, or a mission takeoff item.
    Takeoff,
    /// AUTO.LAND, or a mission land item.
    Land,
    /// OFFBOARD.
    Offboard,
    /// Anything else (hold, RTL, manual).
    Other,
}

/// One steering question; positions local NED metres (z down), velocities m/s, yaw radians clockwise from North.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteerInput {
    /// Vehicle time, seconds.
    pub now_s: f64,
    /// Vehicle position.
    pub pos_ned: [f64; 3],
    /// Vehicle velocity.
    pub vel_ned: [f64; 3],
    /// Vehicle yaw.
    pub yaw_rad: f64,
    /// Where to go (the current waypoint); z is NaN while landing (PX4 leaves the land setpoint's z unset).
    pub goal_ned: [f64; 3],
    /// Where the leg started (the previous waypoint).
    pub prev_goal_ned: [f64; 3],
    /// PX4's desired velocity for this setpoint, if it sent one (trajectory point 0); unset axes are NaN.
    pub desired_vel_ned: Option<[f64; 3]>,
    /// Navigation state.
    pub nav: Nav,
    /// Armed and flying.
    pub airborne: bool,
}

/// A setpoint: local NED position, optional velocity and optional yaw (radians clockwise from North).
///
/// While landing, PX4-Avoidance answers as PX4's own land setpoint does: x, y held, z unset (NaN) and a
/// descent velocity in `vel_ned[2]`, so PX4 descends into the ground and its land detector can fire.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteerOutput {
    /// Position setpoint; an axis may be NaN (unset) only when `vel_ned` sets it.
    pub pos_ned: [f64; 3],
    /// Velocity setpoint per axis, m/s; `None` = unset.
    pub vel_ned: [Option<f64>; 3],
    /// Yaw setpoint.
    pub yaw_rad: Option<f64>,
    /// Yaw-rate setpoint, rad/s; `None` = unset (PX4 then makes its feed-forward from the yaw setpoint's steps).
    pub yaw_rate_rad_s: Option<f64>,
}

impl SteerOutput {
    /// A plain position setpoint.
    pub fn position(pos_ned: [f64; 3], yaw_rad: Option<f64>) -> Self {
        Self {
            pos_ned,
            vel_ned: [None; 3],
            yaw_rad,
            yaw_rate_rad_s: None,
        }
    }

    /// Every axis is set by a finite position or a finite velocity.
    pub fn is_complete(&self) -> bool {
        (0..3).all(|i| self.pos_ned[i].is_finite() || self.vel_ned[i].is_some_and(f64::is_finite))
    }
}

/// Decides the next setpoint; `None` means "cannot plan" (the companion then mirrors PX4's own setpoint).
pub trait Steer: Send {
    /// One steering step.
    fn steer(&mut self, input: &SteerInput) -> Option<SteerOutput>;
}

/// No obstacles to avoid: head straight for the goal.
#[derive(Debug, Clone, Copy, Default)]
pub struct Straight;

impl Steer for Straight {
    fn steer(&mut self, input: &SteerInput) -> Option<SteerOutput> {
        let d = [
            input.goal_ned[0] - input.pos_ned[0],
            input.goal_ned[1] - input.pos_ned[1],
        ];
        let yaw = (d[0].hypot(d[1]) > 0.5).then(|| d[1].atan2(d[0]));
        Some(SteerOutput::position(input.goal_ned, yaw))
    }
}

/// Never plans: the companion mirrors PX4's setpoint (the interface's required fallback).
#[derive(Debug, Clone, Copy, Default)]
pub struct MirrorSetpoint;

impl Steer for MirrorSetpoint {
    fn steer(&mut self, _: &SteerInput) -> Option<SteerOutput> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_heads_for_the_goal() {
        let mut s = Straight;
        let input = SteerInput {
            now_s: 0.0,
            pos_ned: [0.0, 0.0, -5.0],
            vel_ned: [0.0; 3],
            yaw_rad: 0.0,
            goal_ned: [0.0, 10.0, -5.0],
            prev_goal_ned: [0.0; 3],
            desired_vel_ned: None,
            nav: Nav::Mission,
            airborne: true,
        };
        let out = s.steer(&input).unwrap();
        assert_eq!(out.pos_ned, [0.0, 10.0, -5.0]);
        assert!(
            (out.yaw_rad.unwrap() - std::f64::consts::FRAC_PI_2).abs() < 1e-12,
            "East is +90 degrees"
        );
        assert_eq!(MirrorSetpoint.steer(&input), None);
    }
}
