//! Which PX4 release the mock acts as: the version AUTOPILOT_VERSION reports, and whether the release has the
//! obstacle-avoidance interface (`COM_OBS_AVOID`; PX4 removed it in v1.16.0), so a client's version rules can
//! be tested without PX4.

/// A PX4 release number (the mock models v1.14; any number can be reported, to test a client's rules).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Px4Release {
    /// Major number.
    pub major: u8,
    /// Minor number.
    pub minor: u8,
    /// Patch number.
    pub patch: u8,
}

impl Default for Px4Release {
    fn default() -> Self {
        Self::V1_14_0
    }
}

impl Px4Release {
    /// PX4 v1.14.0, the release the mock models.
    pub const V1_14_0: Px4Release = Px4Release {
        major: 1,
        minor: 14,
        patch: 0,
    };

    /// Reads `1.16.2` or `v1.16.2`.
    pub fn parse(text: &str) -> Result<Px4Release, String> {
        let t = text.trim();
        let numbers: Vec<Option<u8>> = t
            .strip_prefix('v')
            .unwrap_or(t)
            .split('.')
            .map(|p| p.parse().ok())
            .collect();
        match numbers[..] {
            [Some(major), Some(minor), Some(patch)] if major > 0 => Ok(Px4Release { major, minor, patch }),
            _ => Err(format!(
                "{text:?}: expected a PX4 release MAJOR.MINOR.PATCH, e.g. 1.16.2"
            )),
        }
    }

    /// AUTOPILOT_VERSION.flight_sw_version: major, minor, patch, then 255 (an official release).
    pub fn flight_sw_version(self) -> u32 {
        (u32::from(self.major) << 24) | (u32::from(self.minor) << 16) | (u32::from(self.patch) << 8) | 255
    }

    /// Whether `COM_OBS_AVOID` and the avoidance interface exist (before v1.16).
    pub fn has_avoidance_interface(self) -> bool {
        (self.major, self.minor) < (1, 16)
    }

    /// Whether Collision Prevention acts in Position mode with `MPC_POS_MODE` `mode`: before v1.16 only the
    /// velocity-based modes call it (0, 3; the default 4 ignores every range message), from v1.16 only the
    /// acceleration-based one (4).
    pub fn cp_acts_in_position_mode(self, mode: f64) -> bool {
        if (self.major, self.minor) < (1, 16) {
            mode == 0.0 || mode == 3.0
        } else {
            mode == 4.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn releases_parse_and_encode_as_px4_does() {
        let r = Px4Release::parse("v1.16.2").unwrap();
        assert_eq!(r.flight_sw_version(), 0x0110_02FF);
        assert!(!r.has_avoidance_interface());
        assert_eq!(Px4Release::default().flight_sw_version(), (1 << 24) | (14 << 16) | 255);
        assert!(Px4Release::parse("1.15.4").unwrap().has_avoidance_interface());
        assert!(!Px4Release::parse("1.18.0").unwrap().has_avoidance_interface());
        let (v14, v16) = (Px4Release::V1_14_0, Px4Release::parse("1.16.2").unwrap());
        assert!(!v14.cp_acts_in_position_mode(4.0) && v14.cp_acts_in_position_mode(3.0));
        assert!(v16.cp_acts_in_position_mode(4.0) && !v16.cp_acts_in_position_mode(0.0));
        for bad in ["0.16.0", "1.16", "1.16.2.1", "1.300.0", "x", ""] {
            assert!(Px4Release::parse(bad).is_err(), "{bad}");
        }
    }
}
