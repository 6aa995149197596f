//! Following the mission in AUTO.MISSION: one update walks the items from the current one, consuming those
//! done at once (speed, jumps, reached waypoints) until one gives a setpoint to fly.

use std::time::Duration;

use mavlink::dialects::common::MavSeverity;

use super::{NavCtx, NavEvent, NavKind, Navigator, Phase, heading_to};
use crate::dynamics::{Ned, Setpoint};
use crate::modes::FlightMode;

impl Navigator {
    pub(super) fn mission(&mut self, ctx: &NavCtx, ev: &mut Vec<NavEvent>) -> Setpoint {
        // The speed as the update began: a DO_CHANGE_SPEED takes effect from the next update.
        let cruise = self.speed_m_s.unwrap_or(ctx.p.cruise_m_s);
        // Instant items are consumed in one update; the bound stops DO_JUMP loops.
        for _ in 0..=self.items.len() {
            if self.mission_finished || self.current >= self.items.len() {
                self.finish_mission(ctx, ev);
                return self.hold_sp(ctx);
            }
            let step = match self.items[self.current].1 {
                NavKind::Instant => {
                    self.advance(ev);
                    ItemStep::Next
                }
                NavKind::Speed { m_s } => {
                    self.speed_m_s = Some(m_s);
                    self.advance(ev);
                    ItemStep::Next
                }
                NavKind::Jump { to, repeat } => {
                    self.jump(to, repeat, ev);
                    ItemStep::Next
                }
                NavKind::Rtl => {
                    self.advance(ev);
                    self.mode = FlightMode::Rtl;
                    self.phase = Phase::Start;
                    ev.push(NavEvent::Mode(FlightMode::Rtl));
                    ItemStep::Fly(self.rtl(ctx))
                }
                NavKind::Takeoff { target, xy_set } => self.takeoff_item(ctx, cruise, target, xy_set, ev),
                NavKind::Waypoint {
                    target,
                    hold_s,
                    acc_rad_m,
                    forever,
                } => {
                    let acc = acc_rad_m.unwrap_or(ctx.p.acc_rad_m);
                    let hold = (!forever).then_some(hold_s);
                    self.waypoint_item(ctx, cruise, target, acc, hold, ev)
                }
                NavKind::Land { xy } => self.land_item(ctx, cruise, xy, ev),
            };
            if let ItemStep::Fly(sp) = step {
                return sp;
            }
        }
        self.hold_sp(ctx)
    }

    /// The first update past the last item: hold where the vehicle is and say so.
    fn finish_mission(&mut self, ctx: &NavCtx, ev: &mut Vec<NavEvent>) {
        if self.mission_finished {
            return;
        }
        self.mission_finished = true;
        self.phase = Phase::Finished;
        self.hold = ctx.body.pos_ned;
        // PX4 v1.14's texts (navigator's mission.cpp), with the tab that marks an event twin.
        let text = if ctx.landed {
            "Mission finished, landed\t"
        } else {
            "Mission finished, loitering\t"
        };
        ev.push(NavEvent::Text(MavSeverity::MAV_SEVERITY_INFO, text.into()));
    }

    /// DO_JUMP to item `to`, `repeat` times (-1: forever), then on to the next item.
    fn jump(&mut self, to: usize, repeat: i32, ev: &mut Vec<NavEvent>) {
        let done = &mut self.jumps[self.current];
        if to < self.items.len() && (repeat < 0 || *done < repeat) {
            *done += 1;
            self.current = to;
            self.phase = Phase::Start;
            ev.push(NavEvent::Current(to as u16));
        } else {
            self.advance(ev);
        }
    }

    /// A takeoff item: climb in place to at least the takeoff altitude, then go to its position if it has one.
    fn takeoff_item(
        &mut self,
        ctx: &NavCtx,
        cruise: f64,
        target: Ned,
        xy_set: bool,
        ev: &mut Vec<NavEvent>,
    ) -> ItemStep {
        let (pos, p) = (ctx.body.pos_ned, ctx.p);
        let z = target.z.min(-p.takeoff_alt_m);
        if self.phase == Phase::Start {
            self.phase = if pos.z <= z + p.alt_rad_m {
                Phase::Approach
            } else {
                Phase::Climb { xy: (pos.x, pos.y), z }
            };
        }
        if let Phase::Climb { xy, z } = self.phase {
            if (pos.z - z).abs() <= p.alt_rad_m {
                self.phase = Phase::Approach;
            } else {
                return ItemStep::Fly(self.goto(
                    Ned::new(xy.0, xy.1, z),
                    cruise,
                    p.takeoff_speed_m_s,
                    p.down_m_s,
                    None,
                ));
            }
        }
        let goal = if xy_set {
            Ned::new(target.x, target.y, z)
        } else {
            Ned::new(pos.x, pos.y, z)
        };
        if (goal - pos).xy().norm() <= p.acc_rad_m {
            self.advance(ev);
            return ItemStep::Next;
        }
        ItemStep::Fly(self.goto(goal, cruise, p.up_m_s, p.down_m_s, heading_to(&pos, &goal)))
    }

    /// A waypoint: reach it within `acc` (metres, horizontally) and the altitude radius, then hold for `hold`
    /// seconds (`None`: loiter forever).
    fn waypoint_item(
        &mut self,
        ctx: &NavCtx,
        cruise: f64,
        target: Ned,
        acc: f64,
        hold: Option<f64>,
        ev: &mut Vec<NavEvent>,
    ) -> ItemStep {
        let (pos, p) = (ctx.body.pos_ned, ctx.p);
        if self.phase == Phase::Start {
            self.phase = Phase::Approach;
        }
        let sp = self.goto(target, cruise, p.up_m_s, p.down_m_s, heading_to(&pos, &target));
        match self.phase {
            Phase::Approach => {
                if (target - pos).xy().norm() <= acc && (target.z - pos.z).abs() <= p.alt_rad_m {
                    self.phase = Phase::Hold {
                        until: hold.map(|h| ctx.now + Duration::from_secs_f64(h)),
                    };
                    if hold.is_none() {
                        ev.push(NavEvent::Reached(self.current as u16));
                    }
                    return ItemStep::Next;
                }
                ItemStep::Fly(sp)
            }
            Phase::Hold { until: Some(t) } if ctx.now >= t => {
                self.advance(ev);
                ItemStep::Next
            }
            _ => ItemStep::Fly(sp),
        }
    }

    /// A land item: go to its position (if any) at the current height, then descend until landed.
    fn land_item(&mut self, ctx: &NavCtx, cruise: f64, xy: Option<(f64, f64)>, ev: &mut Vec<NavEvent>) -> ItemStep {
        let (pos, p) = (ctx.body.pos_ned, ctx.p);
        if self.phase == Phase::Start {
            self.phase = match xy {
                Some(_) => Phase::LandApproach { z: pos.z },
                None => Phase::Descend { xy: (pos.x, pos.y) },
            };
        }
        match self.phase {
            Phase::LandApproach { z } => {
                let (n, e) = xy.unwrap_or((pos.x, pos.y));
                let goal = Ned::new(n, e, z);
                if (goal - pos).xy().norm() <= p.acc_rad_m.min(1.0) {
                    self.phase = Phase::Descend { xy: (n, e) };
                    return ItemStep::Next;
                }
                ItemStep::Fly(self.goto(goal, cruise, p.up_m_s, p.down_m_s, heading_to(&pos, &goal)))
            }
            Phase::Descend { xy } => {
                // A land item is reached when the land detector says landed (mission_block.cpp
                // l. 101-103), not at touchdown.
                if ctx.landed {
                    self.advance(ev);
                    self.hold = pos;
                    return ItemStep::Next;
                }
                ItemStep::Fly(self.descend(ctx, xy))
            }
            _ => ItemStep::Fly(self.hold_sp(ctx)),
        }
    }
}

/// What one mission item asks of the update.
enum ItemStep {
    /// The item is done or the phase moved on: look at the current item again in the same update.
    Next,
    /// Fly this setpoint.
    Fly(Setpoint),
}
