//! Mission items reduced to what the navigator flies: the kind of each NAV item and its target in local NED.

use mavlink::dialects::common::{MISSION_ITEM_INT_DATA, MavCmd};

use crate::dynamics::Ned;
use crate::mission_items::{is_global_frame, is_relative_alt};
use geodesy::LocalProjection;

/// A mission item reduced to what the navigator flies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NavKind {
    /// Climb to `target.z`, then go to its x/y when `xy_set`.
    Takeoff {
        /// Target, local NED metres.
        target: Ned,
        /// False when the item had no position (climb in place).
        xy_set: bool,
    },
    /// Fly to `target` and wait.
    Waypoint {
        /// Target, local NED metres.
        target: Ned,
        /// Hold time at the waypoint, seconds.
        hold_s: f64,
        /// Acceptance radius overriding NAV_ACC_RAD, metres.
        acc_rad_m: Option<f64>,
        /// Loiter forever (LOITER_UNLIM).
        forever: bool,
    },
    /// Land.
    Land {
        /// (north_m, east_m) to land at; None: where the vehicle is.
        xy: Option<(f64, f64)>,
    },
    /// Return to launch.
    Rtl,
    /// DO_JUMP.
    Jump {
        /// Item index to jump to.
        to: usize,
        /// Repeat count (-1 = forever).
        repeat: i32,
    },
    /// DO_CHANGE_SPEED.
    Speed {
        /// New cruise speed, m/s.
        m_s: f64,
    },
    /// Anything done instantly (camera, servo, ...).
    Instant,
}

/// Convert stored items to navigator items (x,y as degrees × 1e7, z relative or AMSL).
pub fn nav_items(items: &[MISSION_ITEM_INT_DATA], proj: &LocalProjection, origin_alt_m: f64) -> Vec<(MavCmd, NavKind)> {
    items
        .iter()
        .map(|it| {
            let xy_set = it.x != 0 || it.y != 0;
            let (n, e) = proj.project(f64::from(it.x) * 1e-7, f64::from(it.y) * 1e-7);
            let alt = if is_relative_alt(it.frame) {
                f64::from(it.z)
            } else {
                f64::from(it.z) - origin_alt_m
            };
            let target = Ned::new(n, e, -alt);
            let global = is_global_frame(it.frame);
            let kind = match it.command {
                MavCmd::MAV_CMD_NAV_TAKEOFF | MavCmd::MAV_CMD_NAV_VTOL_TAKEOFF => NavKind::Takeoff {
                    target,
                    xy_set: xy_set && global,
                },
                MavCmd::MAV_CMD_NAV_WAYPOINT | MavCmd::MAV_CMD_NAV_LOITER_TO_ALT | MavCmd::MAV_CMD_NAV_LOITER_TURNS => {
                    NavKind::Waypoint {
                        target,
                        hold_s: if it.command == MavCmd::MAV_CMD_NAV_WAYPOINT {
                            f64::from(it.param1.max(0.0))
                        } else {
                            0.0
                        },
                        acc_rad_m: (it.command == MavCmd::MAV_CMD_NAV_WAYPOINT && it.param2 > 0.0)
                            .then_some(f64::from(it.param2)),
                        forever: false,
                    }
                }
                MavCmd::MAV_CMD_NAV_LOITER_TIME => NavKind::Waypoint {
                    target,
                    hold_s: f64::from(it.param1.max(0.0)),
                    acc_rad_m: None,
                    forever: false,
                },
                MavCmd::MAV_CMD_NAV_LOITER_UNLIM => NavKind::Waypoint {
                    target,
                    hold_s: 0.0,
                    acc_rad_m: None,
                    forever: true,
                },
                MavCmd::MAV_CMD_NAV_LAND | MavCmd::MAV_CMD_NAV_VTOL_LAND => NavKind::Land {
                    xy: (xy_set && global).then_some((n, e)),
                },
                MavCmd::MAV_CMD_NAV_RETURN_TO_LAUNCH => NavKind::Rtl,
                MavCmd::MAV_CMD_DO_JUMP => NavKind::Jump {
                    to: it.param1.max(0.0) as usize,
                    repeat: it.param2 as i32,
                },
                MavCmd::MAV_CMD_DO_CHANGE_SPEED if it.param2 > 0.0 => NavKind::Speed {
                    m_s: f64::from(it.param2),
                },
                _ => NavKind::Instant,
            };
            (it.command, kind)
        })
        .collect()
}
