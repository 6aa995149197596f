//! PX4 flight modes and how HEARTBEAT encodes them (`custom_mode`, `base_mode`).
//!
//! `custom_mode = (sub_mode << 24) | (main_mode << 16)`, as PX4's `px4_custom_mode` union.

use mavlink::dialects::common::MavModeFlag;

/// PX4 main mode AUTO.
pub const MAIN_AUTO: u8 = 4;
/// PX4 main mode POSCTL.
pub const MAIN_POSCTL: u8 = 3;
/// PX4 main mode OFFBOARD.
pub const MAIN_OFFBOARD: u8 = 6;

/// The flight modes the mock flies.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlightMode {
    /// POSCTL: flown by MANUAL_CONTROL sticks, with Collision Prevention ([`crate::posctl`]).
    Posctl,
    /// AUTO.TAKEOFF.
    Takeoff,
    /// AUTO.LOITER (Hold).
    Loiter,
    /// AUTO.MISSION.
    Mission,
    /// AUTO.RTL.
    Rtl,
    /// AUTO.LAND.
    Land,
    /// OFFBOARD.
    Offboard,
}

impl FlightMode {
    /// PX4 (main_mode, sub_mode).
    pub fn px4_modes(self) -> (u8, u8) {
        match self {
            FlightMode::Posctl => (MAIN_POSCTL, 0),
            FlightMode::Takeoff => (MAIN_AUTO, 2),
            FlightMode::Loiter => (MAIN_AUTO, 3),
            FlightMode::Mission => (MAIN_AUTO, 4),
            FlightMode::Rtl => (MAIN_AUTO, 5),
            FlightMode::Land => (MAIN_AUTO, 6),
            FlightMode::Offboard => (MAIN_OFFBOARD, 0),
        }
    }

    /// The mode for PX4 (main, sub); None for modes the mock does not fly.
    pub fn from_px4(main: u8, sub: u8) -> Option<Self> {
        match (main, sub) {
            (MAIN_POSCTL, _) => Some(FlightMode::Posctl),
            (MAIN_AUTO, 2) => Some(FlightMode::Takeoff),
            (MAIN_AUTO, 3) => Some(FlightMode::Loiter),
            (MAIN_AUTO, 4) => Some(FlightMode::Mission),
            (MAIN_AUTO, 5) => Some(FlightMode::Rtl),
            (MAIN_AUTO, 6) => Some(FlightMode::Land),
            (MAIN_OFFBOARD, _) => Some(FlightMode::Offboard),
            _ => None,
        }
    }

    /// HEARTBEAT `custom_mode`.
    pub fn custom_mode(self) -> u32 {
        let (main, sub) = self.px4_modes();
        (u32::from(sub) << 24) | (u32::from(main) << 16)
    }

    /// Decode a HEARTBEAT `custom_mode`.
    pub fn from_custom_mode(custom_mode: u32) -> Option<Self> {
        Self::from_px4(((custom_mode >> 16) & 0xFF) as u8, (custom_mode >> 24) as u8)
    }

    /// True for the AUTO modes (where the avoidance interface is active).
    pub fn is_auto(self) -> bool {
        self.px4_modes().0 == MAIN_AUTO
    }

    /// HEARTBEAT `base_mode` as PX4 fills it.
    pub fn base_mode(self, armed: bool) -> MavModeFlag {
        let mut f = MavModeFlag::MAV_MODE_FLAG_CUSTOM_MODE_ENABLED;
        f |= match self {
            FlightMode::Posctl => {
                MavModeFlag::MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
                    | MavModeFlag::MAV_MODE_FLAG_STABILIZE_ENABLED
                    | MavModeFlag::MAV_MODE_FLAG_GUIDED_ENABLED
            }
            _ => {
                MavModeFlag::MAV_MODE_FLAG_AUTO_ENABLED
                    | MavModeFlag::MAV_MODE_FLAG_STABILIZE_ENABLED
                    | MavModeFlag::MAV_MODE_FLAG_GUIDED_ENABLED
            }
        };
        if armed {
            f |= MavModeFlag::MAV_MODE_FLAG_SAFETY_ARMED;
        }
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn custom_mode_matches_px4_encoding() {
        assert_eq!(FlightMode::Mission.custom_mode(), (4 << 24) | (4 << 16));
        assert_eq!(FlightMode::Offboard.custom_mode(), 6 << 16);
        for m in [
            FlightMode::Posctl,
            FlightMode::Takeoff,
            FlightMode::Loiter,
            FlightMode::Mission,
            FlightMode::Rtl,
            FlightMode::Land,
            FlightMode::Offboard,
        ] {
            assert_eq!(FlightMode::from_custom_mode(m.custom_mode()), Some(m));
        }
        assert_eq!(FlightMode::from_px4(1, 0), None);
        assert_eq!(FlightMode::Loiter.base_mode(false).bits(), 29);
        assert_eq!(FlightMode::Loiter.base_mode(true).bits(), 157);
    }
}
