//! Lockstep on the pilot's sticks: once a pilot sends MANUAL_CONTROL to the vehicle, armed or in Position mode,
//! a lockstep simulation holds its clock while the latest stick is older than [`STICK_LOCKSTEP_AGE`], so the stick
//! stream never gaps in vehicle time however fast the clock runs or however busy the machine is (at a high
//! speed factor a few milliseconds of wall time would otherwise exceed `COM_RC_LOSS_T`).

use std::time::Duration;

use mavlink::dialects::common::MavSeverity;

use crate::modes::FlightMode;
use crate::vehicle::Vehicle;

/// The vehicle waits for the next stick once the latest is this old: two periods of a 20 Hz pilot, well
/// inside PX4's default `COM_RC_LOSS_T` (0.5 s).
pub const STICK_LOCKSTEP_AGE: Duration = Duration::from_millis(100);

impl Vehicle {
    /// True while the vehicle, armed or in Position mode (whose arming check needs fresh sticks), waits for
    /// the next stick of a pilot that has sent some.
    pub(crate) fn stick_lockstep_blocked(&self) -> bool {
        (self.armed || self.nav.mode() == FlightMode::Posctl)
            && !self.manual.stick_wait_over
            && self
                .manual
                .sticks
                .received_at()
                .is_some_and(|at| self.now.saturating_sub(at) > STICK_LOCKSTEP_AGE)
    }

    /// Go on without the stick (the wait timed out); the manual-control-loss failsafe takes over. Waits again
    /// once sticks come back.
    pub(crate) fn stick_lockstep_release(&mut self) {
        self.manual.stick_wait_over = true;
        self.text(
            MavSeverity::MAV_SEVERITY_WARNING,
            "Lockstep: no sticks in time, going on",
        );
    }
}
