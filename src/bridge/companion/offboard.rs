//! Flying the mission's waypoints ourselves in OFFBOARD mode (any PX4, including 1.15+ without the avoidance
//! interface): SET_POSITION_TARGET_LOCAL_NED at 20 Hz from the same planner, streaming before the mode switch,
//! goal by goal; when the last goal is reached the session commands LAND.

use std::sync::Arc;
use std::time::Duration;

use mavlink::dialects::common::{MavFrame, MavMessage, PositionTargetTypemask, SET_POSITION_TARGET_LOCAL_NED_DATA};
use tokio::sync::watch;
use tokio::task::JoinHandle;

use super::steer::{Nav, Steer, SteerInput, SteerOutput};
use super::steer_worker::SteerWorker;
use crate::bridge::wire::exchange::Target;
use crate::bridge::wire::link::{Link, Sender};
use crate::bridge::wire::vehicle::VehicleView;
use crate::model::Mission;

/// Setpoint period (20 Hz; PX4 leaves OFFBOARD after 0.5 s without one).
pub const SETPOINT_PERIOD: Duration = Duration::from_millis(50);

/// The goals, local NED metres: takeoff point, waypoints, and the land item's position at the previous
/// altitude (PX4 flies there, then descends in LAND).
pub fn goals(mission: &Mission) -> Vec<[f64; 3]> {
    crate::lfs::cp_model::waypoints(mission)
}

/// Goal sequencing: which goal is current, and when all are reached.
#[derive(Debug, Clone)]
pub struct Pilot {
    goals: Vec<[f64; 3]>,
    index: usize,
    acceptance_m: f64,
    start: Option<[f64; 3]>,
}

impl Pilot {
    /// A pilot through `goals`, each reached within `acceptance_m` (3-D).
    pub fn new(goals: Vec<[f64; 3]>, acceptance_m: f64) -> Self {
        Self {
            goals,
            index: 0,
            acceptance_m,
            start: None,
        }
    }

    /// The last goal, once every goal is reached (where to hold until LAND).
    pub fn last_goal(&self) -> Option<[f64; 3]> {
        if self.finished() {
            self.goals.last().copied()
        } else {
            None
        }
    }

    /// True once the last goal was reached.
    pub fn finished(&self) -> bool {
        self.index >= self.goals.len()
    }

    /// The current (goal, previous goal), advancing past goals reached from `pos_ned`.
    pub fn goal(&mut self, pos_ned: [f64; 3]) -> Option<([f64; 3], [f64; 3])> {
        let start = *self.start.get_or_insert(pos_ned);
        while let Some(g) = self.goals.get(self.index) {
            let d = (0..3).map(|k| (g[k] - pos_ned[k]).powi(2)).sum::<f64>().sqrt();
            if d > self.acceptance_m {
                break;
            }
            self.index += 1;
        }
        let g = *self.goals.get(self.index)?;
        let prev = if self.index == 0 {
            start
        } else {
            self.goals[self.index - 1]
        };
        Some((g, prev))
    }
}

fn setpoint_msg(target: Target, time_boot_ms: u32, sp: &SteerOutput) -> MavMessage {
    use PositionTargetTypemask as M;
    let mut mask = M::POSITION_TARGET_TYPEMASK_VX_IGNORE
        | M::POSITION_TARGET_TYPEMASK_VY_IGNORE
        | M::POSITION_TARGET_TYPEMASK_VZ_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AX_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AY_IGNORE
        | M::POSITION_TARGET_TYPEMASK_AZ_IGNORE
        | M::POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE;
    if sp.yaw_rad.is_none() {
        mask |= M::POSITION_TARGET_TYPEMASK_YAW_IGNORE;
    }
    MavMessage::SET_POSITION_TARGET_LOCAL_NED(SET_POSITION_TARGET_LOCAL_NED_DATA {
        time_boot_ms,
        x: sp.pos_ned[0] as f32,
        y: sp.pos_ned[1] as f32,
        z: sp.pos_ned[2] as f32,
        vx: 0.0,
        vy: 0.0,
        vz: 0.0,
        afx: 0.0,
        afy: 0.0,
        afz: 0.0,
        yaw: sp.yaw_rad.unwrap_or(0.0) as f32,
        yaw_rate: 0.0,
        type_mask: mask,
        target_system: target.system,
        target_component: target.component,
        coordinate_frame: MavFrame::MAV_FRAME_LOCAL_NED,
    })
}

/// Progress of the offboard pilot, for the session.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PilotProgress {
    /// At least one setpoint went out (the mode switch may follow).
    pub streaming: bool,
    /// Every goal was reached.
    pub finished: bool,
}

/// Streams setpoints until aborted; `PilotProgress` tells the session when to switch modes and when to land.
pub fn spawn(
    link: Arc<Link>,
    target: Target,
    pilot: Pilot,
    steer: Box<dyn Steer>,
) -> (JoinHandle<()>, watch::Receiver<PilotProgress>) {
    let (tx, rx) = watch::channel(PilotProgress::default());
    (tokio::spawn(run(link, target, pilot, steer, tx)), rx)
}

async fn run(
    link: Arc<Link>,
    target: Target,
    mut pilot: Pilot,
    steer: Box<dyn Steer>,
    tx: watch::Sender<PilotProgress>,
) {
    let clock = link.clock();
    let mut rx = link.subscribe();
    let mut view = VehicleView::default();
    let mut worker = SteerWorker::new(steer);
    let mut next = clock.now();
    loop {
        let now = clock.now();
        if now >= next {
            next = now + SETPOINT_PERIOD;
            let pose = view.pose;
            let leg = pose.and_then(|p| pilot.goal(p.pos_ned).map(|g| (p, g)));
            let input = leg.map(|(p, (goal, prev))| SteerInput {
                now_s: now.as_secs_f64(),
                pos_ned: p.pos_ned,
                vel_ned: p.vel_ned,
                yaw_rad: p.yaw_rad.unwrap_or(0.0),
                goal_ned: goal,
                prev_goal_ned: prev,
                desired_vel_ned: None,
                nav: Nav::Offboard,
                airborne: view.armed,
            });
            if !worker.poll(input, now).await {
                return;
            }
            let sp = match (leg, worker.latest(now, Duration::MAX)) {
                (Some(_), Some(Some(out))) => Some(out),
                // Cannot plan, or no result yet: straight at the goal.
                (Some((_, (goal, _))), _) => Some(SteerOutput::position(goal, None)),
                // After the last goal: hold the last goal (the session lands); before a position: nothing.
                (None, _) => pilot.last_goal().map(|g| SteerOutput::position(g, None)),
            };
            if let Some(sp) = sp {
                let ms = view.pose.map_or(0, |p| p.time_boot_ms);
                let _ = link.send(Sender::Gcs, &setpoint_msg(target, ms, &sp)).await;
                tx.send_if_modified(|p| {
                    let changed = !p.streaming || p.finished != pilot.finished();
                    p.streaming = true;
                    p.finished = pilot.finished();
                    changed
                });
            }
        }
        let wake = clock.wall_until(next);
        view.update_within(&mut rx, &clock, wake).await;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::SIM_HOME;

    #[test]
    fn mission2_goals_and_sequencing() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.plan");
        let m = Mission::load(&path, SIM_HOME).unwrap();
        let g = goals(&m);
        assert_eq!(g.len(), 3, "takeoff, waypoint, land: {g:?}");
        assert_eq!(g[0][2], -10.0);
        assert_eq!(g[2][2], -10.0, "land goal keeps the altitude");
        let mut p = Pilot::new(g.clone(), 1.0);
        let (goal, prev) = p.goal([0.0, 0.0, 0.0]).unwrap();
        assert_eq!(goal, g[0]);
        assert_eq!(prev, [0.0, 0.0, 0.0]);
        let (goal, prev) = p.goal([g[0][0], g[0][1], g[0][2] + 0.5]).unwrap();
        assert_eq!((goal, prev), (g[1], g[0]));
        assert_eq!(p.goal(g[1]).map(|x| x.0), Some(g[2]));
        assert!(!p.finished());
        assert_eq!(p.goal(g[2]), None);
        assert!(p.finished());
    }

    #[test]
    fn setpoint_masks() {
        let t = Target {
            system: 1,
            component: 1,
        };
        let with_yaw = setpoint_msg(t, 5, &SteerOutput::position([1.0, 2.0, -3.0], Some(0.3)));
        let MavMessage::SET_POSITION_TARGET_LOCAL_NED(m) = with_yaw else {
            panic!()
        };
        assert!(
            !m.type_mask
                .contains(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_IGNORE)
        );
        assert!(
            !m.type_mask
                .contains(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_X_IGNORE)
        );
        assert_eq!((m.x, m.z, m.target_system), (1.0, -3.0, 1));
        let no_yaw = setpoint_msg(t, 5, &SteerOutput::position([0.0; 3], None));
        let MavMessage::SET_POSITION_TARGET_LOCAL_NED(m) = no_yaw else {
            panic!()
        };
        assert!(
            m.type_mask
                .contains(PositionTargetTypemask::POSITION_TARGET_TYPEMASK_YAW_IGNORE)
        );
    }
}
