//! The pilot of a Collision Prevention flight: in Position mode, sticks toward the next mission waypoint.
//!
//! Per tick it takes the vehicle's local NED position and heading and gives the sticks PX4 reads from
//! `MANUAL_CONTROL`: pitch forward, roll right (both -1..1, in the heading frame as Position mode reads
//! them), throttle 0..1 (0.5 holds the altitude) and no yaw. The horizontal stick points at the waypoint,
//! its length `gain x distance` capped at `max_stick`; the throttle leaves 0.5 by `climb_gain x altitude
//! error` (capped) only when the altitude is off by more than `alt_band_m`. A waypoint counts as reached
//! within `acceptance_m` horizontally and `alt_acceptance_m` vertically; a pilot that does not reach it within its bound (the leg's length at
//! `min_speed_m_s`, plus `grace_s`) gives up with the reason, so a vehicle held back by Collision Prevention
//! ends as a timeout, never a hang. Sticks move at most `slew_per_s` (in PX4's -1..1 units), and are
//! centred at `end_slew_per_s` before the pilot reports the end: PX4 takes a stick moving faster than
//! COM_RC_STICK_OV (30 % per second, filtered) in LAND as the pilot taking over. Pure and deterministic: the
//! bridge and the LFS fly the same pilot.

/// The pilot's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PilotParams {
    /// Stick per metre to the waypoint.
    pub gain_per_m: f64,
    /// Largest horizontal stick (0.7 is about 4.9 m/s at PX4's defaults MPC_VEL_MANUAL 10, MPC_XY_MAN_EXPO 0.6).
    pub max_stick: f64,
    /// Waypoint acceptance radius, metres (horizontal).
    pub acceptance_m: f64,
    /// Waypoint acceptance in altitude, metres.
    pub alt_acceptance_m: f64,
    /// Throttle per metre of altitude error.
    pub climb_gain_per_m: f64,
    /// Largest throttle offset from 0.5.
    pub max_climb: f64,
    /// Altitude error within which the throttle stays at 0.5, metres.
    pub alt_band_m: f64,
    /// The slowest progress a pilot accepts, m/s: a leg of L metres must be flown within L / this + grace.
    pub min_speed_m_s: f64,
    /// Extra time per leg, seconds.
    pub grace_s: f64,
    /// Fastest stick movement, PX4 units (-1..1) per second.
    pub slew_per_s: f64,
    /// Fastest stick movement while centring at the end (below PX4's takeover rate).
    pub end_slew_per_s: f64,
}

impl Default for PilotParams {
    fn default() -> Self {
        Self {
            gain_per_m: 0.2,
            max_stick: 0.7,
            acceptance_m: 1.0,
            alt_acceptance_m: 1.0,
            climb_gain_per_m: 0.15,
            max_climb: 0.4,
            alt_band_m: 0.3,
            min_speed_m_s: 0.5,
            grace_s: 30.0,
            slew_per_s: 1.0,
            end_slew_per_s: 0.15,
        }
    }
}

/// Stick positions as PX4 reads them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sticks {
    /// Forward (+) / back, -1..1.
    pub pitch: f64,
    /// Right (+) / left, -1..1.
    pub roll: f64,
    /// 0..1; 0.5 holds the altitude.
    pub throttle: f64,
}

impl Sticks {
    /// Centred: hold position and altitude.
    pub const CENTRED: Sticks = Sticks {
        pitch: 0.0,
        roll: 0.0,
        throttle: 0.5,
    };

    /// `MANUAL_CONTROL` fields `x` (pitch), `y` (roll), `z` (throttle 0..1000), `r` (yaw): PX4's scaling.
    pub fn to_mavlink(&self) -> (i16, i16, i16, i16) {
        let axis = |v: f64| (v.clamp(-1.0, 1.0) * 1000.0).round() as i16;
        let z = (self.throttle.clamp(0.0, 1.0) * 1000.0).round() as i16;
        (axis(self.pitch), axis(self.roll), z, 0)
    }
}

/// What the pilot does this tick.
#[derive(Debug, Clone, PartialEq)]
pub enum PilotStep {
    /// Fly with these sticks.
    Fly(Sticks),
    /// Every waypoint reached: hand over to LAND.
    Finished,
    /// A waypoint not reached within its bound: why.
    Stuck(String),
}

/// Waypoint sequencing with a time bound per leg.
#[derive(Debug, Clone)]
pub struct CpPilot {
    goals: Vec<[f64; 3]>,
    index: usize,
    params: PilotParams,
    leg_deadline_s: Option<f64>,
    /// The sticks last given and when.
    last: (Sticks, Option<f64>),
    /// Why the pilot gave up, once it did (it centres the sticks first).
    given_up: Option<String>,
}

impl CpPilot {
    /// A pilot through `goals` (local NED metres: takeoff point, waypoints, the land point at altitude).
    pub fn new(goals: Vec<[f64; 3]>, params: PilotParams) -> Self {
        Self {
            goals,
            index: 0,
            params,
            leg_deadline_s: None,
            last: (Sticks::CENTRED, None),
            given_up: None,
        }
    }

    /// The waypoint flown to now, if any is left.
    pub fn goal(&self) -> Option<[f64; 3]> {
        self.goals.get(self.index).copied()
    }

    /// The sticks at time `now_s` (seconds, any origin) from `pos_ned` with heading `yaw_rad`, slewed; the
    /// end (finished or given up) once they are centred.
    pub fn step(&mut self, now_s: f64, pos_ned: [f64; 3], yaw_rad: f64) -> PilotStep {
        let (wanted, rate) = match self.wanted(now_s, pos_ned, yaw_rad) {
            PilotStep::Fly(s) => (s, self.params.slew_per_s),
            _ => (Sticks::CENTRED, self.params.end_slew_per_s),
        };
        let dt = self.last.1.map_or(0.0, |t| (now_s - t).max(0.0));
        let max = rate * dt;
        let prev = self.last.0;
        let toward = |from: f64, to: f64, scale: f64| {
            let step = (to - from).clamp(-max / scale, max / scale);
            if (to - from - step).abs() < 1e-9 {
                to
            } else {
                from + step
            }
        };
        let sticks = Sticks {
            pitch: toward(prev.pitch, wanted.pitch, 1.0),
            roll: toward(prev.roll, wanted.roll, 1.0),
            throttle: toward(prev.throttle, wanted.throttle, 2.0),
        };
        self.last = (sticks, Some(now_s));
        if sticks != Sticks::CENTRED {
            return PilotStep::Fly(sticks);
        }
        match (&self.given_up, self.goal()) {
            (Some(why), _) => PilotStep::Stuck(why.clone()),
            (None, None) => PilotStep::Finished,
            (None, Some(_)) => PilotStep::Fly(sticks),
        }
    }

    /// The sticks wanted now, before slewing.
    fn wanted(&mut self, now_s: f64, pos_ned: [f64; 3], yaw_rad: f64) -> PilotStep {
        if let Some(why) = &self.given_up {
            return PilotStep::Stuck(why.clone());
        }
        while let Some(g) = self.goal() {
            let horizontal = (g[0] - pos_ned[0]).hypot(g[1] - pos_ned[1]);
            if horizontal > self.params.acceptance_m || (g[2] - pos_ned[2]).abs() > self.params.alt_acceptance_m {
                break;
            }
            self.index += 1;
            self.leg_deadline_s = None;
        }
        let Some(goal) = self.goal() else {
            return PilotStep::Finished;
        };
        let p = &self.params;
        let deadline = *self
            .leg_deadline_s
            .get_or_insert(now_s + dist3(goal, pos_ned) / p.min_speed_m_s + p.grace_s);
        if now_s > deadline {
            let why = format!(
                "the pilot did not reach waypoint {} of {} within its bound ({:.1} m away)",
                self.index + 1,
                self.goals.len(),
                dist3(goal, pos_ned)
            );
            self.given_up = Some(why.clone());
            return PilotStep::Stuck(why);
        }
        PilotStep::Fly(sticks_toward(p, pos_ned, yaw_rad, goal))
    }
}

/// The sticks that fly from `pos_ned` with heading `yaw_rad` toward `goal`.
pub fn sticks_toward(p: &PilotParams, pos_ned: [f64; 3], yaw_rad: f64, goal: [f64; 3]) -> Sticks {
    let (dn, de) = (goal[0] - pos_ned[0], goal[1] - pos_ned[1]);
    let d = dn.hypot(de);
    let len = (p.gain_per_m * d).min(p.max_stick);
    let (un, ue) = if d > 1e-6 { (dn / d, de / d) } else { (0.0, 0.0) };
    // World North/East into the heading frame: forward along the nose, right 90 degrees clockwise of it.
    let (s, c) = yaw_rad.sin_cos();
    let pitch = len * (c * un + s * ue);
    let roll = len * (-s * un + c * ue);
    // Altitude error, up positive (NED down is negative up).
    let up_err = pos_ned[2] - goal[2];
    let throttle = if up_err.abs() <= p.alt_band_m {
        0.5
    } else {
        0.5 + (p.climb_gain_per_m * up_err).clamp(-p.max_climb, p.max_climb)
    };
    Sticks { pitch, roll, throttle }
}

fn dist3(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sticks_point_at_the_goal_in_the_heading_frame() {
        let p = PilotParams::default();
        // Goal 10 m north, nose north: full forward stick, no roll, altitude held.
        let s = sticks_toward(&p, [0.0, 0.0, -5.0], 0.0, [10.0, 0.0, -5.0]);
        assert!(
            (s.pitch - 0.7).abs() < 1e-9 && s.roll.abs() < 1e-9 && s.throttle == 0.5,
            "{s:?}"
        );
        // Nose east: the northern goal is to the left.
        let s = sticks_toward(&p, [0.0, 0.0, -5.0], std::f64::consts::FRAC_PI_2, [10.0, 0.0, -5.0]);
        assert!(s.pitch.abs() < 1e-9 && (s.roll + 0.7).abs() < 1e-9, "{s:?}");
        // Close: the stick shrinks with the distance; 2 m too low: climb.
        let s = sticks_toward(&p, [0.0, 0.0, -3.0], 0.0, [1.0, 0.0, -5.0]);
        assert!((s.pitch - 0.2).abs() < 1e-9 && (s.throttle - 0.8).abs() < 1e-9, "{s:?}");
        assert_eq!(Sticks::CENTRED.to_mavlink(), (0, 0, 500, 0));
        assert_eq!(s.to_mavlink(), (200, 0, 800, 0));
    }

    /// Steps every 0.05 s from `t0` for `secs` at one position; the last step.
    fn hold(pilot: &mut CpPilot, t0: f64, secs: f64, pos: [f64; 3]) -> PilotStep {
        let n = (secs / 0.05).round() as usize;
        (0..=n)
            .map(|k| pilot.step(t0 + k as f64 * 0.05, pos, 0.0))
            .last()
            .unwrap()
    }

    #[test]
    fn waypoints_in_turn_then_finished_with_the_sticks_centred() {
        let mut pilot = CpPilot::new(vec![[0.0, 0.0, -5.0], [20.0, 0.0, -5.0]], PilotParams::default());
        // The throttle rises at the slew rate: 0.5 of PX4's range per second is 0.25 of MAVLink's 0..1.
        assert!(
            matches!(hold(&mut pilot, 0.0, 0.2, [0.0, 0.0, 0.0]), PilotStep::Fly(s) if (s.throttle - 0.6).abs() < 1e-6)
        );
        assert_eq!(pilot.goal(), Some([0.0, 0.0, -5.0]));
        assert!(
            matches!(hold(&mut pilot, 1.0, 1.0, [0.0, 0.0, -4.5]), PilotStep::Fly(s) if (s.pitch - 0.7).abs() < 1e-9)
        );
        assert_eq!(pilot.goal(), Some([20.0, 0.0, -5.0]));
        // Reached: the sticks come back to the centre slowly (0.7 / 0.15 = 4.7 s), then the pilot reports the end.
        assert!(matches!(pilot.step(2.05, [19.5, 0.2, -5.1], 0.0), PilotStep::Fly(s) if s.pitch > 0.6));
        assert!(matches!(hold(&mut pilot, 2.1, 4.0, [19.5, 0.2, -5.1]), PilotStep::Fly(s) if s.pitch > 0.0));
        assert_eq!(hold(&mut pilot, 6.15, 0.7, [19.5, 0.2, -5.1]), PilotStep::Finished);
    }

    #[test]
    fn a_pilot_held_back_gives_up_with_its_reason() {
        let mut pilot = CpPilot::new(vec![[20.0, 0.0, -5.0]], PilotParams::default());
        // 20 m at 0.5 m/s plus 30 s: 70 s.
        assert!(matches!(pilot.step(0.0, [0.0, 0.0, -5.0], 0.0), PilotStep::Fly(_)));
        assert!(matches!(hold(&mut pilot, 68.0, 1.9, [5.0, 0.0, -5.0]), PilotStep::Fly(s) if s.pitch > 0.6));
        // Given up at 70 s: the sticks are centred first, then the reason.
        assert!(
            matches!(pilot.step(70.05, [5.0, 0.0, -5.0], 0.0), PilotStep::Fly(s) if s.pitch < 0.7 && s.pitch > 0.0)
        );
        match hold(&mut pilot, 70.1, 5.0, [5.0, 0.0, -5.0]) {
            PilotStep::Stuck(why) => assert!(why.contains("waypoint 1 of 1") && why.contains("15.0 m"), "{why}"),
            other => panic!("{other:?}"),
        }
    }
}
