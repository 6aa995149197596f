//! Named profiles of the embedded mock autopilot: which reference its avoidance flights are fitted to. A
//! profile is a set of PX4 parameter values and mock model constants applied through the mock's builder,
//! so `mock_autopilot` stays independent of this crate.
//!
//! - `px4-sitl` (the default): fitted to real PX4 v1.14 SITL (`tests/data/px4-flights`, and its repeat
//!   flights for the flight-to-flight scatter; see docs/validation/mock-vs-px4.md).
//! - `competition`: fitted to the competition's recorded Gazebo flights (`tests/data/hfs-flights`).

use mock_autopilot::dynamics::Tuning;
use mock_autopilot::{Builder, ParamValue};

/// One profile: PX4 parameters (set at boot, before the test's own) and the mock's model constants.
#[derive(Debug, Clone, PartialEq)]
pub struct MockProfile {
    /// The profile's name.
    pub name: String,
    /// PX4 parameters the vehicle boots with, beside PX4's defaults.
    pub params: Vec<(String, f64)>,
    /// The mock's model constants (not PX4 parameters).
    pub tuning: Tuning,
}

/// A profile's name, as `mock.profile` takes it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum ProfileName {
    /// `px4-sitl`: fitted to real PX4 v1.14 SITL (SIH).
    #[default]
    #[serde(rename = "px4-sitl")]
    Px4Sitl,
    /// `competition`: fitted to the competition's recorded Gazebo flights.
    #[serde(rename = "competition")]
    Competition,
}

/// The default profile's name.
pub const DEFAULT_PROFILE: &str = "px4-sitl";

/// Every profile's name, the default first.
pub const PROFILE_NAMES: [&str; 2] = [DEFAULT_PROFILE, "competition"];

/// `competition`: horizontal speed limit (MPC_XY_VEL_MAX, m/s), calibrated on how fast the recorded flights flew;
/// a vehicle-side limit the companion does not read (docs/design-constants.md#competition-speed-limit).
pub const COMPETITION_SPEED_LIMIT_M_S: f64 = 1.4;

/// `px4-sitl`: horizontal speed limit (MPC_XY_VEL_MAX, m/s), fitted to real PX4 v1.14 SITL: it stands in for
/// PX4's braking and controller lag (docs/design-constants.md#px4-sitl-speed-limit-and-velocity-gain).
pub const PX4_SITL_SPEED_LIMIT_M_S: f64 = 1.7;

/// `px4-sitl`: the mock's velocity-loop gain (1/s), fitted with the speed limit above: PX4 turns wider and later
/// than a point mass (docs/design-constants.md#px4-sitl-speed-limit-and-velocity-gain).
pub const PX4_SITL_VEL_GAIN: f64 = 1.3;

/// `px4-sitl`: RMS of the mock's seeded horizontal gusts (m/s² per axis, correlation time 1 s), fitted so the
/// mock disagrees with itself flight to flight as PX4 does (docs/design-constants.md#px4-sitl-gusts).
pub const PX4_SITL_GUST_ACC_M_S2: f64 = 0.1;

impl MockProfile {
    /// The profile called `name`, if there is one.
    pub fn by_name(name: &str) -> Option<Self> {
        let (params, tuning): (Vec<(&str, f64)>, Tuning) = match name {
            "px4-sitl" => (
                vec![("MPC_XY_VEL_MAX", PX4_SITL_SPEED_LIMIT_M_S)],
                Tuning {
                    vel_gain: PX4_SITL_VEL_GAIN,
                    gust_acc_m_s2: PX4_SITL_GUST_ACC_M_S2,
                    ..Tuning::default()
                },
            ),
            "competition" => (vec![("MPC_XY_VEL_MAX", COMPETITION_SPEED_LIMIT_M_S)], Tuning::default()),
            _ => return None,
        };
        Some(Self {
            name: name.to_string(),
            params: params.into_iter().map(|(n, v)| (n.to_string(), v)).collect(),
            tuning,
        })
    }

    /// The profile `name`.
    pub fn of(name: ProfileName) -> Self {
        let named = match name {
            ProfileName::Px4Sitl => "px4-sitl",
            ProfileName::Competition => "competition",
        };
        Self::by_name(named).unwrap_or_else(|| unreachable!("every ProfileName is a profile"))
    }

    /// The profile called `name`, or an error naming the known ones.
    pub fn named(name: &str) -> Result<Self, String> {
        Self::by_name(name).ok_or_else(|| format!("unknown mock profile {name:?}; known: {}", PROFILE_NAMES.join(", ")))
    }

    /// Sets one value: a model constant of [`Tuning`] by its name, or else a PX4 parameter (experiments).
    pub fn set(&mut self, key: &str, value: f64) -> Result<(), String> {
        if !value.is_finite() {
            return Err(format!("{key}: {value} is not a finite number"));
        }
        if self.tuning.set(key, value) {
            return Ok(());
        }
        if !key
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_')
            || key.is_empty()
        {
            return Err(format!(
                "{key:?} is neither a mock model constant nor a PX4 parameter name"
            ));
        }
        self.params.retain(|(n, _)| n != key);
        self.params.push((key.to_string(), value));
        Ok(())
    }

    /// A mock builder flying this profile. PX4 parameters go on as floats; the mock keeps each parameter's
    /// declared type.
    pub fn builder(&self) -> Builder {
        let mut b = mock_autopilot::MockAutopilot::builder().tuning(self.tuning);
        for (name, v) in &self.params {
            b = b.param(name, ParamValue::Float(*v as f32));
        }
        b
    }
}

impl Default for MockProfile {
    fn default() -> Self {
        Self::by_name(DEFAULT_PROFILE).unwrap_or_else(|| unreachable!("the default profile exists"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_is_a_profile_and_unknown_names_are_refused_by_name() {
        for n in PROFILE_NAMES {
            assert_eq!(MockProfile::named(n).map(|p| p.name), Ok(n.to_string()));
        }
        let e = MockProfile::named("gazebo").unwrap_err();
        assert!(
            e.contains("gazebo") && e.contains("px4-sitl") && e.contains("competition"),
            "{e}"
        );
        assert_eq!(MockProfile::default().name, DEFAULT_PROFILE);
        assert_eq!(MockProfile::of(ProfileName::default()).name, DEFAULT_PROFILE);
        assert_eq!(MockProfile::of(ProfileName::Competition).name, "competition");
    }

    #[test]
    fn set_overrides_a_parameter_or_a_constant_and_refuses_nonsense() {
        let mut p = MockProfile::named("competition").unwrap();
        p.set("MPC_XY_VEL_MAX", 2.0).unwrap();
        assert_eq!(p.params, vec![("MPC_XY_VEL_MAX".to_string(), 2.0)]);
        assert!(p.set("mpc xy", 1.0).is_err());
        assert!(p.set("MPC_XY_VEL_MAX", f64::NAN).is_err());
    }
}
