//! What the vehicle keeps of stick and range-sensor input between steps ([`crate::posctl`] acts on it).

use std::time::Duration;

use crate::collision_prevention::RangeInbox;
use crate::modes::FlightMode;
use crate::position_mode::PositionMode;
use crate::sticks::StickInput;

/// Stick and range-sensor input, Position mode's state and the manual-control-loss failsafe.
#[derive(Debug, Clone, Default)]
pub struct ManualState {
    pub(crate) sticks: StickInput,
    pub(crate) ranges: RangeInbox,
    pub(crate) mode: Option<PositionMode>,
    pub(crate) had_sticks: bool,
    pub(crate) loss: Option<Loss>,
    pub(crate) next_echo: Duration,
    /// A lockstep wait for the sticks timed out: no more waits until the next stick.
    pub(crate) stick_wait_over: bool,
}

/// A manual-control-loss failsafe under way.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Loss {
    pub(crate) since: Duration,
    /// The mode the failsafe put the vehicle in; None while holding before the action.
    pub(crate) acted: Option<FlightMode>,
    pub(crate) before: FlightMode,
}
