//! The simulated PX4 vehicle: protocols, navigator, dynamics and telemetry tied together.
//!
//! Sans-IO: `handle(header, msg)` takes input, `step(dt)` advances simulated time by one fixed
//! physics step, and `drain_outbox()` yields the messages to send (as sysid 1 / compid 1).

use std::time::Duration;

use mavlink::MavHeader;
use mavlink::dialects::common::{MavLandedState, MavMessage, MavMissionResult, MavMissionType, MavSeverity, MavState};

use crate::avoidance::Avoidance;
use crate::dynamics::{Body, Limits, Ned, Setpoint, Tuning};
use crate::fence::Fence;
use crate::gusts::{Gusts, flight_seed};
use crate::land_detector::{LandDetector, LandInputs, LandParams};
use crate::manual::ManualState;
use crate::mission_server::{MissionAction, MissionServer};
use crate::modes::FlightMode;
use crate::navigator::{NavCtx, NavEvent, NavParams, Navigator, nav_items};
use crate::params::{ParamReply, ParamTable, ParamValue};
use crate::release::Px4Release;
use crate::telemetry::Streams;
use geodesy::{GeoPoint, LocalProjection, SIM_HOME};

/// Our MAVLink system id.
pub const SYSTEM_ID: u8 = 1;
/// Our MAVLink component id (autopilot).
pub const COMPONENT_ID: u8 = 1;
/// Component id of the obstacle-avoidance companion.
pub const AVOIDANCE_COMPONENT_ID: u8 = 196;

/// Tells whether a position is inside an obstacle (for `--crash-on-collision`).
pub trait CollisionWorld: Send {
    /// A description of the obstacle hit at `pos_ned` (local NED metres), if any.
    fn collision(&self, pos_ned: &Ned) -> Option<String>;
}

/// Static configuration of a vehicle.
pub struct VehicleConfig {
    /// Home / local origin (the vehicle boots on the ground here).
    pub home: GeoPoint,
    /// Every mission upload fails with this code (fault injection).
    pub reject_mission: Option<MavMissionResult>,
    /// Every arming attempt is refused (fault injection).
    pub fail_arm: bool,
    /// Obstacles that crash the vehicle on contact.
    pub collision: Option<Box<dyn CollisionWorld>>,
    /// Parameter overrides applied at boot.
    pub params: Vec<(String, ParamValue)>,
    /// Vehicle time after each boot until the estimator has converged (no GPS fix, home or arming before);
    /// zero here for sans-IO tests, [`crate::preflight::DEFAULT_ESTIMATOR_SETTLE`] in a spawned mock.
    pub estimator_settle: Duration,
    /// The kinematic model's constants (defaults: the mock's original model).
    pub tuning: Tuning,
    /// Seed of the gusts (`tuning.gust_acc_m_s2`): flight k since the vehicle started flies the gusts of
    /// [`crate::gusts::flight_seed`]`(seed, k)`.
    pub seed: u64,
    /// The PX4 release it acts as (AUTOPILOT_VERSION; no `COM_OBS_AVOID` from v1.16).
    pub release: Px4Release,
}

impl Default for VehicleConfig {
    fn default() -> Self {
        Self {
            home: SIM_HOME,
            reject_mission: None,
            fail_arm: false,
            collision: None,
            params: Vec::new(),
            estimator_settle: Duration::ZERO,
            tuning: Tuning::default(),
            seed: 0,
            release: Px4Release::default(),
        }
    }
}

impl std::fmt::Debug for VehicleConfig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VehicleConfig")
            .field("home", &self.home)
            .field("reject_mission", &self.reject_mission)
            .field("fail_arm", &self.fail_arm)
            .field("collision", &self.collision.is_some())
            .field("estimator_settle", &self.estimator_settle)
            .field("tuning", &self.tuning)
            .field("seed", &self.seed)
            .field("release", &self.release)
            .finish()
    }
}

/// A snapshot for tests and benches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleState {
    /// Simulated time since the simulation started.
    pub sim_time: Duration,
    /// Position, local NED metres.
    pub pos_ned: Ned,
    /// Velocity, local NED m/s.
    pub vel_ned: Ned,
    /// Armed?
    pub armed: bool,
    /// Flight mode.
    pub mode: FlightMode,
    /// Landed state as in EXTENDED_SYS_STATE.
    pub landed_state: MavLandedState,
    /// Index of the current mission item.
    pub mission_current: usize,
    /// True after the last mission item completed.
    pub mission_finished: bool,
    /// True after a crash (collision).
    pub crashed: bool,
    /// Mission items on the vehicle (0 until a mission is uploaded).
    pub mission_items: usize,
}

/// The simulated vehicle.
pub struct Vehicle {
    pub(crate) now: Duration,
    pub(crate) boot_at: Duration,
    pub(crate) params: ParamTable,
    params_seen: u64,
    pub(crate) limits: Limits,
    pub(crate) nav_params: NavParams,
    pub(crate) missions: MissionServer,
    pub(crate) nav: Navigator,
    pub(crate) body: Body,
    pub(crate) armed: bool,
    pub(crate) landed: bool,
    pub(crate) landed_since: Duration,
    took_off: bool,
    pub(crate) land_detector: LandDetector,
    land_params: LandParams,
    pub(crate) home_ned: Ned,
    pub(crate) origin: GeoPoint,
    pub(crate) proj: LocalProjection,
    pub(crate) fence: Fence,
    pub(crate) fence_breached: bool,
    pub(crate) avoidance: Avoidance,
    pub(crate) offboard: Option<(Setpoint, Duration)>,
    pub(crate) manual: ManualState,
    pub(crate) streams: Streams,
    reached: Option<(u16, u8, Duration)>,
    pub(crate) outbox: Vec<MavMessage>,
    /// The id of the last chunked STATUSTEXT.
    text_id: u16,
    pub(crate) crashed: bool,
    pub(crate) failsafe: bool,
    pub(crate) fail_arm: bool,
    pub(crate) collision: Option<Box<dyn CollisionWorld>>,
    due: Vec<u32>,
    pub(crate) estimator_settle: Duration,
    pub(crate) feasibility_pending: bool,
    seed: u64,
    pub(crate) flight_sw_version: u32,
    pub(crate) release: Px4Release,
    flights: u64,
    gusts: Gusts,
}

#[expect(deprecated, reason = "PX4 still speaks mission items and the avoidance interface")]
impl Vehicle {
    /// A vehicle on the ground at `cfg.home`, disarmed, in AUTO.LOITER.
    pub fn new(cfg: VehicleConfig) -> Self {
        let mut params = ParamTable::default();
        if !cfg.release.has_avoidance_interface() {
            params.remove("COM_OBS_AVOID");
        }
        for (name, v) in &cfg.params {
            params.set(name, *v);
        }
        let proj = LocalProjection::new(cfg.home);
        Self {
            now: Duration::ZERO,
            boot_at: Duration::ZERO,
            limits: Limits::from_params(&params).with_tuning(cfg.tuning),
            nav_params: NavParams::from_params(&params),
            land_params: LandParams::from_params(&params),
            params_seen: params.version(),
            params,
            missions: MissionServer::new(cfg.reject_mission),
            nav: Navigator::new(),
            body: Body::default(),
            armed: false,
            landed: true,
            landed_since: Duration::ZERO,
            took_off: false,
            land_detector: LandDetector::default(),
            home_ned: Ned::zeros(),
            origin: cfg.home,
            proj,
            fence: Fence::default(),
            fence_breached: false,
            avoidance: Avoidance::default(),
            offboard: None,
            manual: ManualState::default(),
            streams: Streams::default(),
            reached: None,
            outbox: Vec::new(),
            text_id: 0,
            crashed: false,
            failsafe: false,
            fail_arm: cfg.fail_arm,
            collision: cfg.collision,
            due: Vec::new(),
            estimator_settle: cfg.estimator_settle,
            feasibility_pending: false,
            seed: cfg.seed,
            flight_sw_version: cfg.release.flight_sw_version(),
            release: cfg.release,
            flights: 0,
            gusts: Gusts::calm(),
        }
    }

    /// Simulated time since the simulation started.
    pub fn now(&self) -> Duration {
        self.now
    }

    /// Milliseconds since the (last) boot, as `time_boot_ms`.
    pub fn time_boot_ms(&self) -> u32 {
        self.now.saturating_sub(self.boot_at).as_millis() as u32
    }

    /// Read-only parameter table.
    pub fn params(&self) -> &ParamTable {
        &self.params
    }

    /// A snapshot of the vehicle state.
    pub fn state(&self) -> VehicleState {
        VehicleState {
            sim_time: self.now,
            pos_ned: self.body.pos_ned,
            vel_ned: self.body.vel_ned,
            armed: self.armed,
            mode: self.nav.mode(),
            landed_state: self.landed_state(),
            mission_current: self.nav.current(),
            mission_finished: self.nav.mission_finished(),
            crashed: self.crashed,
            mission_items: self.nav.count(),
        }
    }

    /// The messages produced since the last drain.
    pub fn drain_outbox(&mut self) -> std::vec::Drain<'_, MavMessage> {
        self.outbox.drain(..)
    }

    /// Simulate a reboot: disarmed on the ground at home; parameters and stored plans survive.
    pub fn reboot(&mut self) {
        self.boot_at = self.now;
        self.body = Body::default();
        self.armed = false;
        self.landed = true;
        self.landed_since = self.now;
        self.took_off = false;
        self.land_detector.reset_landed();
        self.crashed = false;
        self.failsafe = false;
        self.offboard = None;
        self.reset_manual();
        self.reached = None;
        self.avoidance = Avoidance::default();
        self.streams = Streams::default();
        self.home_ned = Ned::zeros();
        self.nav = Navigator::new();
        self.reload_mission();
        self.outbox.clear();
    }

    pub(crate) fn text(&mut self, severity: MavSeverity, text: &str) {
        self.text_id = self.text_id.wrapping_add(1).max(1);
        let parts = crate::status_text::chunks(severity, text, self.text_id);
        self.outbox.extend(parts.into_iter().map(MavMessage::STATUSTEXT));
    }

    /// EXTENDED_SYS_STATE landed state.
    pub fn landed_state(&self) -> MavLandedState {
        if self.landed {
            MavLandedState::MAV_LANDED_STATE_ON_GROUND
        } else if self.nav.is_landing() {
            MavLandedState::MAV_LANDED_STATE_LANDING
        } else if self.armed
            && self.body.pos_ned.z > -self.nav_params.takeoff_alt_m.max(1.0)
            && self.body.vel_ned.z < -0.1
        {
            MavLandedState::MAV_LANDED_STATE_TAKEOFF
        } else {
            MavLandedState::MAV_LANDED_STATE_IN_AIR
        }
    }

    /// Handle one incoming message from `header`.
    pub fn handle(&mut self, header: &MavHeader, msg: &MavMessage) {
        let from = (header.system_id.min(255) as u8, header.component_id);
        if let Some((sys, _)) = target_of(msg)
            && sys != 0
            && sys != SYSTEM_ID
        {
            return;
        }
        match msg {
            MavMessage::HEARTBEAT(hb) if header.component_id == AVOIDANCE_COMPONENT_ID => {
                self.avoidance.on_heartbeat(self.now, hb.system_status);
            }
            MavMessage::TRAJECTORY_REPRESENTATION_WAYPOINTS(t) if header.component_id == AVOIDANCE_COMPONENT_ID => {
                self.avoidance.on_trajectory(self.now, t);
            }
            MavMessage::PARAM_REQUEST_LIST(_) => self.param_reply(self.params.on_request_list()),
            MavMessage::PARAM_REQUEST_READ(r) => self.param_reply(self.params.on_request_read(r)),
            MavMessage::PARAM_SET(s) => {
                let r = self.params.on_set(s);
                self.param_reply(r);
            }
            MavMessage::COMMAND_LONG(c) => {
                let p = [c.param1, c.param2, c.param3, c.param4, c.param5, c.param6, c.param7];
                self.on_command(from, c.command, p, false);
            }
            MavMessage::COMMAND_INT(c) => {
                let p = [c.param1, c.param2, c.param3, c.param4, c.x as f32, c.y as f32, c.z];
                self.on_command(from, c.command, p, true);
            }
            MavMessage::SET_POSITION_TARGET_LOCAL_NED(s) => self.on_offboard_setpoint(s),
            MavMessage::MANUAL_CONTROL(m) => self.on_manual_control(m),
            MavMessage::OBSTACLE_DISTANCE(m) => self.on_obstacle_distance(m),
            MavMessage::MISSION_SET_CURRENT(s) => {
                if self.nav.set_current(usize::from(s.seq)) {
                    self.send_mission_current();
                }
            }
            _ => {
                let actions = self.missions.on_message(msg, from, self.now);
                self.apply_mission_actions(actions);
            }
        }
    }

    fn param_reply(&mut self, r: ParamReply) {
        match r {
            ParamReply::Values(v) => self.outbox.extend(v),
            ParamReply::Text(sev, t) => self.text(sev, &t),
        }
    }

    fn apply_mission_actions(&mut self, actions: Vec<MissionAction>) {
        for a in actions {
            match a {
                MissionAction::Send(m) => self.outbox.push(*m),
                MissionAction::Text(sev, t) => self.text(sev, &t),
                MissionAction::Updated(MavMissionType::MAV_MISSION_TYPE_MISSION) => self.reload_mission(),
                MissionAction::Updated(MavMissionType::MAV_MISSION_TYPE_FENCE) => self.reload_fence(),
                MissionAction::Updated(_) => {}
            }
        }
    }

    fn reload_mission(&mut self) {
        let items = &self.missions.plan(MavMissionType::MAV_MISSION_TYPE_MISSION).items;
        self.nav.set_mission(nav_items(items, &self.proj, self.origin.alt_m));
        self.check_feasibility();
        self.reload_fence();
    }

    fn reload_fence(&mut self) {
        let items = &self.missions.plan(MavMissionType::MAV_MISSION_TYPE_FENCE).items;
        // Validated on upload, so this only fails if storage was bypassed.
        self.fence = Fence::from_items(items, &self.proj).unwrap_or_default();
        self.fence_breached = false;
    }

    /// Switch mode (no checks: commands check before calling).
    pub(crate) fn set_mode(&mut self, mode: FlightMode, takeoff_alt_m: f64) {
        self.nav.set_mode(mode, &self.body, takeoff_alt_m);
        self.avoidance.reset();
        // Streams restart in phase with the mode switch: a flight is then the same whatever wall time the
        // command arrived at (only the phase of PX4's free-running streams differs).
        self.streams.rephase(self.now);
        self.send_mission_current();
    }

    pub(crate) fn arm(&mut self) {
        if !self.armed {
            self.armed = true;
            self.took_off = false;
            self.landed_since = self.now;
            self.failsafe = false;
            self.crashed = false;
            self.home_ned = self.body.pos_ned;
            let t = self.limits.tuning;
            self.gusts = Gusts::new(flight_seed(self.seed, self.flights), t.gust_acc_m_s2, t.gust_tau_s);
            self.flights += 1;
            self.text(MavSeverity::MAV_SEVERITY_INFO, "Armed by external command");
            self.outbox.push(self.home_position());
            // Armed in AUTO.MISSION the flight starts here: streams in phase with it, as after a mode switch.
            self.streams.rephase(self.now);
        }
    }

    pub(crate) fn disarm(&mut self, why: &str) {
        if self.armed {
            self.armed = false;
            self.avoidance.reset();
            self.text(MavSeverity::MAV_SEVERITY_INFO, &format!("Disarmed by {why}"));
        }
    }

    /// True while a lockstep simulation must hold its clock: the vehicle flies with avoidance and the
    /// companion has not answered the latest trajectory request yet, or a pilot flies it and its next stick is
    /// due ([`crate::stick_lockstep`]).
    pub fn lockstep_blocked(&self) -> bool {
        (self.armed
            && self.params.f64("COM_OBS_AVOID") >= 1.0
            && self.nav.mode().is_auto()
            && self.avoidance.awaiting_answer(self.now))
            || self.stick_lockstep_blocked()
    }

    /// Go on without the answer (the lockstep wait timed out; the avoidance timeout logic takes over). Said
    /// aloud: from here the flight depends on the machine's load and is no longer repeatable.
    pub fn lockstep_release(&mut self) {
        if self.stick_lockstep_blocked() {
            return self.stick_lockstep_release();
        }
        self.avoidance.release();
        self.text(
            MavSeverity::MAV_SEVERITY_WARNING,
            "Lockstep: no avoidance answer in time, going on",
        );
    }

    /// Advance the simulation by one fixed step `dt`.
    pub fn step(&mut self, dt: Duration) {
        self.now += dt;
        if self.params.version() != self.params_seen {
            self.params_seen = self.params.version();
            self.limits = Limits::from_params(&self.params).with_tuning(self.limits.tuning);
            self.nav_params = NavParams::from_params(&self.params);
            self.land_params = LandParams::from_params(&self.params);
        }
        let actions = self.missions.on_tick(self.now);
        self.apply_mission_actions(actions);
        self.preflight_step();
        self.offboard_failsafe();
        self.manual_loss_step();
        let sp = self.navigate();
        let manual = self.manual_step(dt.as_secs_f64());
        // What the controller tracks this step: PX4's trajectory setpoint, which the land detector watches.
        let vel_sp_ned = match &manual {
            Some((c, _)) => Some(c.vel_ned),
            None => self.body.velocity_setpoint(&sp, &self.limits).map(|(v, _)| v),
        };
        if !self.crashed {
            // Gusts blow while armed and act only in the air.
            let gust = if self.armed {
                self.gusts.step(dt.as_secs_f64())
            } else {
                Ned::zeros()
            };
            let gust = if self.body.on_ground() { Ned::zeros() } else { gust };
            match &manual {
                Some((c, mp)) => self.body.track_manual(c, mp, dt.as_secs_f64(), gust),
                None => self.body.step_disturbed(&sp, &self.limits, dt.as_secs_f64(), gust),
            }
        }
        let inputs = LandInputs::of(self.armed, &self.body, vel_sp_ned.filter(|_| !self.crashed));
        self.land_detector
            .update(self.now, dt.as_secs_f64(), &inputs, &self.land_params);
        self.detect_land_and_takeoff();
        self.check_fence();
        self.check_collision();
        self.send_streams();
    }

    fn navigate(&mut self) -> Setpoint {
        let mut events = Vec::new();
        let ctx = NavCtx {
            now: self.now,
            body: &self.body,
            armed: self.armed,
            p: &self.nav_params,
            home: self.home_ned,
            landed: self.land_detector.landed(),
        };
        let mut sp = self.nav.update(&ctx, &mut events);
        for e in events {
            match e {
                NavEvent::Reached(seq) => {
                    self.reached = Some((seq, 10, self.now));
                }
                NavEvent::Current(_) | NavEvent::Mode(_) => self.send_mission_current(),
                NavEvent::Text(sev, t) => self.text(sev, &t),
            }
        }
        if self.nav.mode() == FlightMode::Offboard && self.armed {
            sp = match self.offboard {
                Some((s, _)) => s,
                None => sp,
            };
        }
        if self.params.f64("COM_OBS_AVOID") >= 1.0 && self.nav.mode().is_auto() && self.armed {
            let mut texts = Vec::new();
            let time_usec = u64::from(self.time_boot_ms()) * 1000;
            self.avoidance
                .set_z_caps(self.nav_params.up_m_s, self.nav_params.down_m_s);
            let (s, msg) = self.avoidance.apply(
                self.now,
                sp,
                self.body.pos_ned,
                (self.nav.setpoint_command(), self.nav.waypoints()),
                time_usec,
                &mut texts,
            );
            sp = s;
            self.outbox.extend(msg);
            for (sev, t) in texts {
                self.text(sev, &t);
            }
        }
        sp
    }

    fn detect_land_and_takeoff(&mut self) {
        let on_ground = self.body.on_ground();
        if self.landed && self.armed && !on_ground && self.body.pos_ned.z < -0.1 {
            self.landed = false;
            self.took_off = true;
            self.text(MavSeverity::MAV_SEVERITY_INFO, "Takeoff detected");
        } else if !self.landed && self.land_detector.landed() {
            // PX4's commander reports the land detector's verdict, not the touchdown (Commander.cpp l. 1984).
            self.landed = true;
            self.landed_since = self.now;
            self.text(MavSeverity::MAV_SEVERITY_INFO, "Landing detected");
        }
        if self.armed && self.landed {
            let secs = |name: &str| self.params.f64(name);
            let on_ground_for = self.now.saturating_sub(self.landed_since).as_secs_f64();
            // A zero or negative COM_DISARM_LAND disables it (commander_params.c l. 200-214, Commander.cpp l. 2136).
            if self.took_off && secs("COM_DISARM_LAND") > 0.0 && on_ground_for >= secs("COM_DISARM_LAND") {
                self.disarm("landing");
            } else if !self.took_off && secs("COM_DISARM_PRFLT") > 0.0 && on_ground_for >= secs("COM_DISARM_PRFLT") {
                self.disarm("auto preflight disarming");
            }
        }
    }

    fn send_streams(&mut self) {
        let mut due = std::mem::take(&mut self.due);
        due.clear();
        self.streams.due(self.now, &mut due);
        for &id in &due {
            if let Some(m) = self.build_message(id) {
                self.outbox.push(m);
            }
        }
        self.due = due;
        // PX4 repeats the last MISSION_ITEM_REACHED up to 10 times at 10 Hz.
        if let Some((seq, left, at)) = self.reached
            && self.now >= at
        {
            self.outbox.push(MavMessage::MISSION_ITEM_REACHED(
                mavlink::dialects::common::MISSION_ITEM_REACHED_DATA { seq },
            ));
            self.reached = (left > 1).then_some((seq, left - 1, at + Duration::from_millis(100)));
        }
    }

    /// The system status for HEARTBEAT.
    pub(crate) fn system_status(&self) -> MavState {
        if self.crashed || self.failsafe {
            MavState::MAV_STATE_CRITICAL
        } else if self.armed {
            MavState::MAV_STATE_ACTIVE
        } else {
            MavState::MAV_STATE_STANDBY
        }
    }
}

/// (target_system, target_component) of messages that carry one.
#[expect(deprecated, reason = "PX4 still speaks mission items and the avoidance interface")]
fn target_of(msg: &MavMessage) -> Option<(u8, u8)> {
    use MavMessage as M;
    Some(match msg {
        M::COMMAND_LONG(m) => (m.target_system, m.target_component),
        M::COMMAND_INT(m) => (m.target_system, m.target_component),
        M::PARAM_SET(m) => (m.target_system, m.target_component),
        M::PARAM_REQUEST_READ(m) => (m.target_system, m.target_component),
        M::PARAM_REQUEST_LIST(m) => (m.target_system, m.target_component),
        M::MISSION_COUNT(m) => (m.target_system, m.target_component),
        M::MISSION_ITEM_INT(m) => (m.target_system, m.target_component),
        M::MISSION_ITEM(m) => (m.target_system, m.target_component),
        M::MISSION_REQUEST_LIST(m) => (m.target_system, m.target_component),
        M::MISSION_REQUEST_INT(m) => (m.target_system, m.target_component),
        M::MISSION_REQUEST(m) => (m.target_system, m.target_component),
        M::MISSION_CLEAR_ALL(m) => (m.target_system, m.target_component),
        M::MISSION_ACK(m) => (m.target_system, m.target_component),
        M::MISSION_SET_CURRENT(m) => (m.target_system, m.target_component),
        M::SET_POSITION_TARGET_LOCAL_NED(m) => (m.target_system, m.target_component),
        _ => return None,
    })
}

#[cfg(test)]
#[path = "vehicle_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "vehicle_landing_tests.rs"]
mod landing_tests;
