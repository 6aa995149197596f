//! The vehicle in Position mode: MANUAL_CONTROL and OBSTACLE_DISTANCE in, stick flight with Collision
//! Prevention, PX4's fused obstacle map echoed back, and the manual-control-loss failsafe.
//!
//! Manual-control loss as PX4 v1.16's commander: sticks older than `COM_RC_LOSS_T` are lost. Once sticks
//! have been seen since arming (PX4 ignores a loss that already held at arming), a loss in a mode not
//! excepted by `COM_RCL_EXCEPT` holds for `COM_FAIL_ACT_T`, then takes the `NAV_RCL_ACT` action (1 Hold,
//! 2 Return, 3 Land, 5 Terminate, 6 Disarm; 0 none). Sticks back during the hold cancel it; after the action
//! only a mode change or a disarm clears it.

use std::time::Duration;

use mavlink::dialects::common::{MANUAL_CONTROL_DATA, MavMessage, MavSeverity, OBSTACLE_DISTANCE_DATA};

use crate::collision_prevention::{CpEvent, CpParams};
use crate::manual::{Loss, ManualState};
use crate::modes::FlightMode;
use crate::position_mode::{ManualCommand, ManualParams, PositionMode};
use crate::sticks::Sticks;
use crate::vehicle::{SYSTEM_ID, Vehicle};

/// PX4 streams its fused obstacle map at 10 Hz on the onboard link of ports 14580/14540, which the mock's
/// ports imitate (1 Hz on a normal GCS link).
const ECHO_PERIOD: Duration = Duration::from_millis(100);

impl Vehicle {
    pub(crate) fn on_manual_control(&mut self, m: &MANUAL_CONTROL_DATA) {
        if m.target == 0 || m.target == SYSTEM_ID {
            self.manual.sticks.on_message(m, self.now);
            self.manual.stick_wait_over = false;
        }
    }

    pub(crate) fn on_obstacle_distance(&mut self, m: &OBSTACLE_DISTANCE_DATA) {
        self.manual.ranges.put(m, self.now);
    }

    /// The sticks unless lost (older than `COM_RC_LOSS_T`).
    pub(crate) fn fresh_sticks(&self) -> Option<Sticks> {
        let timeout = Duration::from_secs_f64(self.params.f64("COM_RC_LOSS_T").clamp(0.0, 60.0));
        self.manual.sticks.fresh(self.now, timeout)
    }

    /// Forgets sticks, ranges and Position mode (reboot).
    pub(crate) fn reset_manual(&mut self) {
        self.manual = ManualState::default();
    }

    /// Position mode's command for this step, None outside armed Position mode.
    pub(crate) fn manual_step(&mut self, dt_s: f64) -> Option<(ManualCommand, ManualParams)> {
        if self.nav.mode() != FlightMode::Posctl || !self.armed || self.crashed {
            self.manual.mode = None;
            return None;
        }
        let sticks = self.fresh_sticks().unwrap_or_default();
        let mp = ManualParams::from_params(&self.params);
        let cpp = CpParams::for_release(&self.params, self.release);
        let mut events = Vec::new();
        let body = self.body;
        let now = self.now;
        let time_usec = u64::from(self.time_boot_ms()) * 1000;
        let m = &mut self.manual;
        let mode = m.mode.get_or_insert_with(|| PositionMode::start(&body));
        let cmd = mode.step(sticks, &body, &mp, (&cpp, &m.ranges, now), dt_s, &mut events);
        if cpp.active() && now >= m.next_echo {
            m.next_echo = now + ECHO_PERIOD;
            let echo = mode.cp.map().to_message(time_usec);
            self.outbox.push(MavMessage::OBSTACLE_DISTANCE(echo));
        }
        for e in events {
            match e {
                CpEvent::Text(t) => self.text(MavSeverity::MAV_SEVERITY_CRITICAL, &t),
                CpEvent::Hold => {
                    self.text(MavSeverity::MAV_SEVERITY_WARNING, "No obstacle data, switching to Hold");
                    self.set_mode(FlightMode::Loiter, self.nav_params.takeoff_alt_m);
                }
            }
        }
        Some((cmd, mp))
    }

    /// Switching to Position mode while armed needs a position and sticks, as PX4's mode requirements.
    pub(crate) fn posctl_refusal(&self) -> Option<&'static str> {
        (!self.estimator_settled() || self.fresh_sticks().is_none())
            .then_some("Switching to Position is currently not possible")
    }

    /// The manual-control-loss failsafe (see the module documentation).
    pub(crate) fn manual_loss_step(&mut self) {
        if !self.armed {
            self.manual.had_sticks = false;
            self.manual.loss = None;
            return;
        }
        let fresh = self.fresh_sticks().is_some();
        self.manual.had_sticks |= fresh;
        let mode = self.nav.mode();
        match self.manual.loss {
            Some(l) if l.acted.is_some_and(|a| a != mode) => self.manual.loss = None,
            Some(l) if l.acted.is_none() && fresh => {
                self.manual.loss = None;
                self.failsafe = false;
                self.text(MavSeverity::MAV_SEVERITY_INFO, "Manual control regained");
                self.set_mode(l.before, self.nav_params.takeoff_alt_m);
            }
            Some(l) if l.acted.is_none() => {
                let delay = Duration::from_secs_f64(self.params.f64("COM_FAIL_ACT_T").clamp(0.0, 25.0));
                if self.now.saturating_sub(l.since) >= delay {
                    self.manual_loss_act(l);
                }
            }
            Some(_) => {}
            None if !fresh && self.manual.had_sticks && !self.manual_loss_excepted(mode) => {
                self.failsafe = true;
                self.text(
                    MavSeverity::MAV_SEVERITY_CRITICAL,
                    "Failsafe: manual control lost, Hold",
                );
                let l = Loss {
                    since: self.now,
                    acted: None,
                    before: mode,
                };
                self.manual.loss = Some(l);
                self.set_mode(FlightMode::Loiter, self.nav_params.takeoff_alt_m);
            }
            None => {}
        }
    }

    fn manual_loss_excepted(&self, mode: FlightMode) -> bool {
        let bits = self.params.f64("COM_RCL_EXCEPT") as i64;
        let action = self.params.f64("NAV_RCL_ACT") as i64;
        action == 0
            || match mode {
                FlightMode::Mission => bits & 1 != 0,
                FlightMode::Loiter | FlightMode::Takeoff => bits & 2 != 0,
                FlightMode::Offboard => bits & 4 != 0,
                _ => false,
            }
    }

    fn manual_loss_act(&mut self, l: Loss) {
        let alt = self.nav_params.takeoff_alt_m;
        let (mode, name) = match self.params.f64("NAV_RCL_ACT") as i64 {
            2 => (Some(FlightMode::Rtl), "Return"),
            3 => (Some(FlightMode::Land), "Land"),
            5 | 6 => (None, "Disarm"),
            _ => (Some(FlightMode::Loiter), "Hold"),
        };
        self.text(
            MavSeverity::MAV_SEVERITY_CRITICAL,
            &format!("Failsafe: manual control lost, {name} activated"),
        );
        match mode {
            Some(m) => {
                self.set_mode(m, alt);
                self.manual.loss = Some(Loss { acted: Some(m), ..l });
            }
            None => self.disarm("failsafe"),
        }
    }
}

#[cfg(test)]
#[path = "posctl_tests.rs"]
mod tests;
