//! What the vehicle should fly in each mode: mission items, takeoff, land, RTL, hold.
//!
//! Pure logic: `update(ctx)` turns the mode, the mission and the body state into a dynamics
//! setpoint plus events (item reached, mode change, texts). Positions are local NED metres.

use std::time::Duration;

use mavlink::dialects::common::{MavCmd, MavSeverity};

use crate::dynamics::{Body, Ned, Setpoint};
use crate::modes::FlightMode;
use crate::params::ParamTable;

pub use crate::nav_items::{NavKind, nav_items};

/// Parameters the navigator reads (cached from the table).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NavParams {
    /// MPC_XY_CRUISE, m/s.
    pub cruise_m_s: f64,
    /// MPC_TKO_SPEED, m/s.
    pub takeoff_speed_m_s: f64,
    /// MPC_Z_VEL_MAX_UP, m/s.
    pub up_m_s: f64,
    /// MPC_Z_VEL_MAX_DN, m/s.
    pub down_m_s: f64,
    /// MPC_LAND_SPEED, m/s.
    pub land_speed_m_s: f64,
    /// MPC_LAND_ALT1 / ALT2, m above ground.
    pub land_alt1_m: f64,
    /// MPC_LAND_ALT2, m.
    pub land_alt2_m: f64,
    /// NAV_ACC_RAD, m.
    pub acc_rad_m: f64,
    /// NAV_MC_ALT_RAD, m.
    pub alt_rad_m: f64,
    /// MIS_TAKEOFF_ALT, m.
    pub takeoff_alt_m: f64,
    /// RTL_RETURN_ALT, m.
    pub rtl_alt_m: f64,
}

impl NavParams {
    /// Read from the parameter table.
    pub fn from_params(p: &ParamTable) -> Self {
        Self {
            cruise_m_s: p.f64("MPC_XY_CRUISE").max(0.1),
            takeoff_speed_m_s: p.f64("MPC_TKO_SPEED").max(0.1),
            up_m_s: p.f64("MPC_Z_VEL_MAX_UP").max(0.1),
            down_m_s: p.f64("MPC_Z_VEL_MAX_DN").max(0.1),
            land_speed_m_s: p.f64("MPC_LAND_SPEED").max(0.1),
            land_alt1_m: p.f64("MPC_LAND_ALT1"),
            land_alt2_m: p.f64("MPC_LAND_ALT2"),
            acc_rad_m: p.f64("NAV_ACC_RAD").max(0.05),
            alt_rad_m: p.f64("NAV_MC_ALT_RAD").max(0.05),
            takeoff_alt_m: p.f64("MIS_TAKEOFF_ALT"),
            rtl_alt_m: p.f64("RTL_RETURN_ALT"),
        }
    }

    /// PX4's landing descent speed at `alt_m` above ground.
    pub fn land_speed_at(&self, alt_m: f64) -> f64 {
        let (hi, lo) = (
            self.land_alt1_m.max(self.land_alt2_m),
            self.land_alt2_m.min(self.land_alt1_m),
        );
        if alt_m >= hi {
            self.down_m_s
        } else if alt_m <= lo || hi - lo < 1e-6 {
            self.land_speed_m_s
        } else {
            self.land_speed_m_s + (self.down_m_s - self.land_speed_m_s) * (alt_m - lo) / (hi - lo)
        }
    }
}

/// What happened during a navigator update.
#[derive(Debug, Clone, PartialEq)]
pub enum NavEvent {
    /// Mission item reached (MISSION_ITEM_REACHED).
    Reached(u16),
    /// The current mission item changed.
    Current(u16),
    /// Switch to this mode.
    Mode(FlightMode),
    /// STATUSTEXT.
    Text(MavSeverity, String),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    Start,
    Climb { xy: (f64, f64), z: f64 },
    Approach,
    Hold { until: Option<Duration> },
    LandApproach { z: f64 },
    Descend { xy: (f64, f64) },
    RtlReturn { z: f64 },
    Finished,
}

/// Mode and mission progress.
#[derive(Debug, Clone)]
pub struct Navigator {
    mode: FlightMode,
    items: Vec<(MavCmd, NavKind)>,
    current: usize,
    phase: Phase,
    hold: Ned,
    jumps: Vec<i32>,
    speed_m_s: Option<f64>,
    takeoff_z: f64,
    mission_finished: bool,
}

/// Inputs of one navigator update.
#[derive(Debug, Clone, Copy)]
pub struct NavCtx<'a> {
    /// Simulated time since boot.
    pub now: Duration,
    /// Vehicle state.
    pub body: &'a Body,
    /// Armed?
    pub armed: bool,
    /// Parameters.
    pub p: &'a NavParams,
    /// Home, local NED.
    pub home: Ned,
    /// The land detector says landed (PX4's `vehicle_land_detected.landed`).
    pub landed: bool,
}

fn heading_to(from: &Ned, to: &Ned) -> Option<f64> {
    let d = to - from;
    (d.xy().norm() > 1.0).then(|| d.y.atan2(d.x))
}

impl Navigator {
    /// Boots in AUTO.LOITER (Hold), like PX4 without RC.
    pub fn new() -> Self {
        Self {
            mode: FlightMode::Loiter,
            items: Vec::new(),
            current: 0,
            phase: Phase::Start,
            hold: Ned::zeros(),
            jumps: Vec::new(),
            speed_m_s: None,
            takeoff_z: -2.5,
            mission_finished: false,
        }
    }

    /// Current flight mode.
    pub fn mode(&self) -> FlightMode {
        self.mode
    }

    /// Index of the current mission item.
    pub fn current(&self) -> usize {
        self.current
    }

    /// Number of mission items.
    pub fn count(&self) -> usize {
        self.items.len()
    }

    /// True once the last mission item was completed.
    pub fn mission_finished(&self) -> bool {
        self.mission_finished
    }

    /// True while descending to land (landed state LANDING).
    pub fn is_landing(&self) -> bool {
        matches!(self.phase, Phase::Descend { .. })
    }

    /// What kind of setpoint PX4's auto flight task flies now, as the MAV_CMD PX4 puts in point 0's
    /// `command` of TRAJECTORY_REPRESENTATION_WAYPOINTS (PX4 1.14 streams/TRAJECTORY_REPRESENTATION_WAYPOINTS.hpp:
    /// takeoff, loiter and land map to their NAV commands, a plain position to `u16::MAX`).
    pub fn setpoint_command(&self) -> u16 {
        match (self.mode, self.phase) {
            (_, Phase::Descend { .. }) => MavCmd::MAV_CMD_NAV_LAND as u16,
            (_, Phase::Climb { .. }) => MavCmd::MAV_CMD_NAV_TAKEOFF as u16,
            (FlightMode::Loiter, _) => MavCmd::MAV_CMD_NAV_LOITER_UNLIM as u16,
            _ => u16::MAX,
        }
    }

    /// Replace the mission (keeps the mode; restarts at item 0).
    pub fn set_mission(&mut self, items: Vec<(MavCmd, NavKind)>) {
        self.jumps = vec![0; items.len()];
        self.items = items;
        self.current = 0;
        self.mission_finished = false;
        self.speed_m_s = None;
        if self.mode == FlightMode::Mission {
            self.phase = Phase::Start;
        }
    }

    /// Make `seq` the current item (MISSION_SET_CURRENT / MISSION_START param1).
    pub fn set_current(&mut self, seq: usize) -> bool {
        if seq >= self.items.len() {
            return false;
        }
        self.current = seq;
        self.mission_finished = false;
        self.phase = Phase::Start;
        true
    }

    /// Enter `mode` from state `body`; `takeoff_alt_m` for AUTO.TAKEOFF.
    pub fn set_mode(&mut self, mode: FlightMode, body: &Body, takeoff_alt_m: f64) {
        self.mode = mode;
        self.hold = body.pos_ned;
        self.takeoff_z = -takeoff_alt_m;
        self.phase = match mode {
            FlightMode::Takeoff => Phase::Climb {
                xy: (body.pos_ned.x, body.pos_ned.y),
                z: -takeoff_alt_m,
            },
            FlightMode::Land => Phase::Descend {
                xy: (body.pos_ned.x, body.pos_ned.y),
            },
            _ => Phase::Start,
        };
        if mode == FlightMode::Mission && self.mission_finished {
            self.current = 0;
            self.mission_finished = false;
        }
    }

    /// Current and next mission waypoint (position, command) for the avoidance interface.
    ///
    /// While a land item is still approached at altitude, PX4's navigator has made the current item a plain
    /// waypoint above the land point at the altitude where the approach began ("move to land"), so that is what
    /// the companion sees: a fixed goal altitude, not the ground.
    pub fn waypoints(&self) -> [Option<(Ned, u16)>; 2] {
        // Outside a mission PX4's triplet is the mode's own target (navigator land.cpp, takeoff.cpp).
        match (self.mode, self.phase) {
            (FlightMode::Land, Phase::Descend { xy }) => {
                return [Some((Ned::new(xy.0, xy.1, 0.0), MavCmd::MAV_CMD_NAV_LAND as u16)), None];
            }
            (FlightMode::Takeoff, Phase::Climb { xy, z }) => {
                return [
                    Some((Ned::new(xy.0, xy.1, z), MavCmd::MAV_CMD_NAV_TAKEOFF as u16)),
                    None,
                ];
            }
            _ => {}
        }
        let mut out = [None, None];
        let mut k = 0;
        for (i, (cmd, kind)) in self.items.iter().enumerate().skip(self.current) {
            let (pos, cmd) = match (kind, self.phase) {
                // PX4 names only takeoff, loiter and land items; a plain position is u16::MAX.
                (NavKind::Takeoff { target, .. }, _) => (*target, MavCmd::MAV_CMD_NAV_TAKEOFF as u16),
                (NavKind::Waypoint { target, .. }, _) => match cmd {
                    MavCmd::MAV_CMD_NAV_LOITER_TIME | MavCmd::MAV_CMD_NAV_LOITER_UNLIM => {
                        (*target, MavCmd::MAV_CMD_NAV_LOITER_UNLIM as u16)
                    }
                    _ => (*target, u16::MAX),
                },
                (NavKind::Land { xy: Some((n, e)) }, Phase::LandApproach { z }) if i == self.current => {
                    (Ned::new(*n, *e, z), u16::MAX)
                }
                (NavKind::Land { xy: Some((n, e)) }, _) => (Ned::new(*n, *e, 0.0), MavCmd::MAV_CMD_NAV_LAND as u16),
                _ => continue,
            };
            out[k] = Some((pos, cmd));
            k += 1;
            if k == 2 {
                break;
            }
        }
        out
    }

    fn goto(&self, target: Ned, h: f64, up: f64, down: f64, yaw: Option<f64>) -> Setpoint {
        Setpoint::Position {
            target_ned: target,
            h_speed_m_s: h,
            up_speed_m_s: up,
            down_speed_m_s: down,
            yaw_rad: yaw,
        }
    }

    fn hold_sp(&self, ctx: &NavCtx) -> Setpoint {
        if self.hold.z >= -0.05 && ctx.body.on_ground() {
            return Setpoint::Idle;
        }
        self.goto(self.hold, ctx.p.cruise_m_s, ctx.p.up_m_s, ctx.p.down_m_s, None)
    }

    /// PX4's land setpoint: hold the land point horizontally, descend at the land speed for the height
    /// (FlightTaskAuto.cpp `_prepareLandSetpoints`, release/1.14 l. 232-301: position (x, y, NaN), velocity
    /// (NaN, NaN, speed)); it keeps pushing into the ground until the land detector fires.
    fn descend(&self, ctx: &NavCtx, xy: (f64, f64)) -> Setpoint {
        let alt = -ctx.body.pos_ned.z;
        Setpoint::XyPositionZVelocity {
            target_xy_ned: xy,
            h_speed_m_s: ctx.p.cruise_m_s,
            vel_z_m_s: ctx.p.land_speed_at(alt),
            yaw_rad: None,
        }
    }

    /// One update: the setpoint to fly and what happened.
    pub fn update(&mut self, ctx: &NavCtx, ev: &mut Vec<NavEvent>) -> Setpoint {
        if !ctx.armed {
            return Setpoint::Idle;
        }
        match self.mode {
            FlightMode::Loiter | FlightMode::Posctl => self.hold_sp(ctx),
            FlightMode::Offboard => self.hold_sp(ctx), // the vehicle overrides with offboard setpoints
            FlightMode::Takeoff => self.takeoff_mode(ctx, ev),
            FlightMode::Land => match self.phase {
                Phase::Descend { xy } => self.descend(ctx, xy),
                _ => self.hold_sp(ctx),
            },
            FlightMode::Rtl => self.rtl(ctx),
            FlightMode::Mission => self.mission(ctx, ev),
        }
    }

    fn takeoff_mode(&mut self, ctx: &NavCtx, ev: &mut Vec<NavEvent>) -> Setpoint {
        let Phase::Climb { xy, z } = self.phase else {
            return self.hold_sp(ctx);
        };
        if (ctx.body.pos_ned.z - z).abs() <= ctx.p.alt_rad_m {
            self.mode = FlightMode::Loiter;
            self.hold = Ned::new(xy.0, xy.1, z);
            ev.push(NavEvent::Mode(FlightMode::Loiter));
        }
        self.goto(
            Ned::new(xy.0, xy.1, z),
            ctx.p.cruise_m_s,
            ctx.p.takeoff_speed_m_s,
            ctx.p.down_m_s,
            None,
        )
    }

    fn rtl(&mut self, ctx: &NavCtx) -> Setpoint {
        let pos = ctx.body.pos_ned;
        if self.phase == Phase::Start {
            self.phase = Phase::Climb {
                xy: (pos.x, pos.y),
                z: pos.z.min(-ctx.p.rtl_alt_m),
            };
        }
        match self.phase {
            Phase::Climb { xy, z } => {
                if (pos.z - z).abs() <= ctx.p.alt_rad_m {
                    self.phase = Phase::RtlReturn { z };
                }
                self.goto(
                    Ned::new(xy.0, xy.1, z),
                    ctx.p.cruise_m_s,
                    ctx.p.up_m_s,
                    ctx.p.down_m_s,
                    None,
                )
            }
            Phase::RtlReturn { z } => {
                let target = Ned::new(ctx.home.x, ctx.home.y, z);
                if (target - pos).xy().norm() <= ctx.p.acc_rad_m.min(1.0) {
                    self.phase = Phase::Descend {
                        xy: (ctx.home.x, ctx.home.y),
                    };
                }
                self.goto(
                    target,
                    ctx.p.cruise_m_s,
                    ctx.p.up_m_s,
                    ctx.p.down_m_s,
                    heading_to(&pos, &target),
                )
            }
            Phase::Descend { xy } => self.descend(ctx, xy),
            _ => self.hold_sp(ctx),
        }
    }

    fn advance(&mut self, ev: &mut Vec<NavEvent>) {
        ev.push(NavEvent::Reached(self.current as u16));
        self.current += 1;
        self.phase = Phase::Start;
        if self.current < self.items.len() {
            ev.push(NavEvent::Current(self.current as u16));
        }
    }
}

impl Default for Navigator {
    fn default() -> Self {
        Self::new()
    }
}

#[path = "nav_mission.rs"]
mod mission;

#[cfg(test)]
#[path = "navigator_tests.rs"]
mod tests;
