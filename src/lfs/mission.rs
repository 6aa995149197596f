//! PX4's mission logic as the simulator needs it: take off to the first item's altitude, fly the items with
//! the acceptance radii NAV_ACC_RAD / NAV_MC_ALT_RAD, fly to the land item's position at altitude, then descend.
//!
//! Positions are planner ENU (x East, y North, z Up, metres) about the home position (the local origin).

use nalgebra::Vector3;

use crate::model::{CMD_LAND, CMD_TAKEOFF, Mission, Param};
use geodesy::frames::north_east_up_to_enu;

/// What PX4 does at a mission item.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ItemKind {
    /// Climb vertically to the item's altitude.
    Takeoff,
    /// Fly to the position.
    Waypoint,
    /// Fly to the position at altitude, then descend and land.
    Land,
}

/// One positional item, ENU metres (z = altitude above home).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MissionTarget {
    /// Position, ENU metres.
    pub position_enu: Vector3<f64>,
    /// Kind.
    pub kind: ItemKind,
}

/// PX4 parameters of the mission logic (metres, m/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MissionParams {
    /// NAV_ACC_RAD: horizontal acceptance radius (PX4 default 2 m; the competition sets 0.5 m).
    pub nav_acc_rad_m: f64,
    /// NAV_MC_ALT_RAD: vertical acceptance (PX4 default 0.8 m; the competition sets 0.5 m).
    pub nav_mc_alt_rad_m: f64,
    /// MIS_TAKEOFF_ALT: minimum takeoff altitude (PX4 default 2.5 m; the competition sets 1 m).
    pub mis_takeoff_alt_m: f64,
    /// MPC_TKO_SPEED: takeoff climb speed (PX4 default 1.5 m/s).
    pub takeoff_speed_m_s: f64,
    /// MPC_LAND_SPEED: landing descent speed (PX4 default 0.7 m/s).
    pub land_speed_m_s: f64,
}

impl Default for MissionParams {
    fn default() -> Self {
        Self {
            nav_acc_rad_m: 2.0,
            nav_mc_alt_rad_m: 0.8,
            mis_takeoff_alt_m: 2.5,
            takeoff_speed_m_s: 1.5,
            land_speed_m_s: 0.7,
        }
    }
}

impl MissionParams {
    /// PX4 defaults overridden by the test's parameters (NAV_ACC_RAD, NAV_MC_ALT_RAD, MIS_TAKEOFF_ALT,
    /// MPC_TKO_SPEED, MPC_LAND_SPEED; non-positive or non-finite values are ignored).
    pub fn from_params(params: &[Param]) -> Self {
        let mut m = Self::default();
        for p in params.iter().filter(|p| p.value.is_finite() && p.value > 0.0) {
            match p.name.as_str() {
                "NAV_ACC_RAD" => m.nav_acc_rad_m = p.value,
                "NAV_MC_ALT_RAD" => m.nav_mc_alt_rad_m = p.value,
                "MIS_TAKEOFF_ALT" => m.mis_takeoff_alt_m = p.value,
                "MPC_TKO_SPEED" => m.takeoff_speed_m_s = p.value,
                "MPC_LAND_SPEED" => m.land_speed_m_s = p.value,
                _ => {}
            }
        }
        m
    }
}

/// Where the vehicle is in the mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// On the ground before the mission starts.
    Ground,
    /// Climbing vertically.
    Takeoff,
    /// Flying to the current item with avoidance.
    Cruise,
    /// Descending at the land item.
    Descend,
    /// Touched down after the land item.
    Landed,
    /// The last item was not a land item: PX4 holds position forever.
    Hold,
}

/// The mission as PX4 flies it.
#[derive(Debug, Clone)]
pub struct MissionRunner {
    targets: Vec<MissionTarget>,
    index: usize,
    phase: Phase,
    params: MissionParams,
    takeoff_alt_m: f64,
    prev_goal_enu: Vector3<f64>,
    /// Altitude kept while flying to a land item's position.
    land_approach_alt_m: Option<f64>,
}

impl MissionRunner {
    /// The positional items of `mission` (local NED converted to ENU); `None` if there are none.
    pub fn new(mission: &Mission, params: MissionParams) -> Option<Self> {
        let targets: Vec<MissionTarget> = mission
            .items
            .iter()
            .filter_map(|it| {
                let p = it.local?;
                let kind = match it.command {
                    CMD_TAKEOFF => ItemKind::Takeoff,
                    CMD_LAND => ItemKind::Land,
                    _ => ItemKind::Waypoint,
                };
                Some(MissionTarget {
                    position_enu: north_east_up_to_enu(p.north_m, p.east_m, p.alt_m),
                    kind,
                })
            })
            .collect();
        Self::from_targets(targets, params)
    }

    /// A runner over explicit targets (ENU); `None` if empty.
    pub fn from_targets(targets: Vec<MissionTarget>, params: MissionParams) -> Option<Self> {
        let first = *targets.first()?;
        // PX4 always takes off first: to the takeoff item's altitude (at least MIS_TAKEOFF_ALT), or to the first
        // item's altitude when the mission does not start with a takeoff.
        let takeoff_alt_m = first.position_enu.z.max(params.mis_takeoff_alt_m);
        Some(Self {
            targets,
            index: 0,
            phase: Phase::Ground,
            params,
            takeoff_alt_m,
            prev_goal_enu: Vector3::zeros(),
            land_approach_alt_m: None,
        })
    }

    /// Current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Index of the current target.
    pub fn index(&self) -> usize {
        self.index
    }

    /// The parameters.
    pub fn params(&self) -> &MissionParams {
        &self.params
    }

    /// The mission's targets, ENU.
    pub fn targets(&self) -> &[MissionTarget] {
        &self.targets
    }

    /// The takeoff altitude, metres.
    pub fn takeoff_alt_m(&self) -> f64 {
        self.takeoff_alt_m
    }

    /// True when the current target is a land item (during its approach and descent).
    pub fn at_land_item(&self) -> bool {
        self.targets.get(self.index).is_some_and(|t| t.kind == ItemKind::Land)
    }

    /// The goal the planner flies to (ENU metres): the current item; a land item at the approach altitude.
    pub fn goal_enu(&self, pos: &Vector3<f64>) -> Vector3<f64> {
        if matches!(self.phase, Phase::Ground | Phase::Takeoff) {
            return Vector3::new(pos.x, pos.y, self.takeoff_alt_m);
        }
        let t = self.targets[self.index.min(self.targets.len() - 1)];
        match (t.kind, self.phase) {
            (ItemKind::Land, Phase::Descend | Phase::Landed) => t.position_enu,
            (ItemKind::Land, _) => {
                let alt = self.land_approach_alt_m.unwrap_or(pos.z);
                Vector3::new(t.position_enu.x, t.position_enu.y, alt)
            }
            _ => t.position_enu,
        }
    }

    /// The previous goal (ENU), for the planner's line pull.
    pub fn prev_goal_enu(&self) -> Vector3<f64> {
        self.prev_goal_enu
    }

    /// Advances the mission for the vehicle at `pos` (ENU); returns true if the target changed.
    pub fn update(&mut self, pos: &Vector3<f64>) -> bool {
        match self.phase {
            Phase::Ground => {
                self.phase = Phase::Takeoff;
                self.prev_goal_enu = *pos;
                true
            }
            Phase::Takeoff => {
                if pos.z < self.takeoff_alt_m - self.params.nav_mc_alt_rad_m {
                    return false;
                }
                if self.targets[0].kind == ItemKind::Takeoff {
                    self.index = 1;
                }
                self.prev_goal_enu = Vector3::new(pos.x, pos.y, self.takeoff_alt_m);
                self.enter_item(pos);
                true
            }
            Phase::Cruise => {
                let g = self.goal_enu(pos);
                let dxy = (g.xy() - pos.xy()).norm();
                if dxy >= self.params.nav_acc_rad_m || (g.z - pos.z).abs() >= self.params.nav_mc_alt_rad_m {
                    return false;
                }
                if self.at_land_item() {
                    self.phase = Phase::Descend;
                    return true;
                }
                self.prev_goal_enu = g;
                self.index += 1;
                self.enter_item(pos);
                true
            }
            Phase::Descend => {
                if pos.z <= 0.0 {
                    self.phase = Phase::Landed;
                    return true;
                }
                false
            }
            Phase::Landed | Phase::Hold => false,
        }
    }

    fn enter_item(&mut self, pos: &Vector3<f64>) {
        self.land_approach_alt_m = None;
        match self.targets.get(self.index) {
            None => self.phase = Phase::Hold,
            Some(t) => {
                if t.kind == ItemKind::Land {
                    self.land_approach_alt_m = Some(pos.z.max(self.prev_goal_enu.z));
                }
                self.phase = Phase::Cruise;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn runner() -> MissionRunner {
        let t = |x: f64, y: f64, z: f64, kind| MissionTarget {
            position_enu: Vector3::new(x, y, z),
            kind,
        };
        MissionRunner::from_targets(
            vec![
                t(0.0, 0.0, 10.0, ItemKind::Takeoff),
                t(50.0, 0.0, 10.0, ItemKind::Waypoint),
                t(50.0, 20.0, 0.0, ItemKind::Land),
            ],
            MissionParams {
                nav_acc_rad_m: 0.5,
                nav_mc_alt_rad_m: 0.5,
                ..Default::default()
            },
        )
        .unwrap()
    }

    #[test]
    fn takeoff_waypoint_land_sequence() {
        let mut m = runner();
        let mut p = Vector3::new(0.0, 0.0, 0.0);
        assert!(m.update(&p));
        assert_eq!(m.phase(), Phase::Takeoff);
        assert_eq!(m.goal_enu(&p), Vector3::new(0.0, 0.0, 10.0));
        p.z = 9.0;
        assert!(!m.update(&p));
        p.z = 9.6;
        assert!(m.update(&p));
        assert_eq!((m.phase(), m.index()), (Phase::Cruise, 1));
        assert_eq!(m.goal_enu(&p), Vector3::new(50.0, 0.0, 10.0));
        p = Vector3::new(49.4, 0.0, 10.0);
        assert!(!m.update(&p), "0.6 m is outside NAV_ACC_RAD 0.5");
        p.x = 49.7;
        assert!(m.update(&p));
        assert!(m.at_land_item());
        // The land item is approached at altitude.
        assert_eq!(m.goal_enu(&p), Vector3::new(50.0, 20.0, 10.0));
        assert_eq!(m.prev_goal_enu(), Vector3::new(50.0, 0.0, 10.0));
        p = Vector3::new(50.0, 19.8, 10.1);
        assert!(m.update(&p));
        assert_eq!(m.phase(), Phase::Descend);
        p.z = 0.0;
        assert!(m.update(&p));
        assert_eq!(m.phase(), Phase::Landed);
    }

    #[test]
    fn params_from_the_test() {
        let p = |n: &str, v: f64| Param {
            name: n.into(),
            value: v,
        };
        let m = MissionParams::from_params(&[
            p("NAV_ACC_RAD", 0.5),
            p("MIS_TAKEOFF_ALT", 1.0),
            p("NAV_MC_ALT_RAD", -1.0),
        ]);
        assert_eq!(
            (m.nav_acc_rad_m, m.mis_takeoff_alt_m, m.nav_mc_alt_rad_m),
            (0.5, 1.0, 0.8)
        );
    }

    #[test]
    fn mission_without_land_ends_in_hold() {
        let mut m = MissionRunner::from_targets(
            vec![MissionTarget {
                position_enu: Vector3::new(0.0, 0.0, 5.0),
                kind: ItemKind::Waypoint,
            }],
            MissionParams::default(),
        )
        .unwrap();
        let p = Vector3::new(0.0, 0.0, 5.0);
        m.update(&p);
        m.update(&p);
        assert_eq!(m.phase(), Phase::Cruise);
        m.update(&p);
        assert_eq!(m.phase(), Phase::Hold);
    }
}
