//! The types a setting can have, and how a flag's text becomes one: numbers, switches, paths, ranges, lists,
//! and the closed sets of names ([`Choice`]: the flight mode, the motion model, the judge edition, ...). A
//! flag's text becomes the key's TOML value, which serde then types like the file's own: one parser for both.

use std::path::PathBuf;

use crate::bridge::{Bench, FlyMode, SimLink, VehicleSim};
use crate::generator::Family;
use crate::judge::Judge;
use crate::lfs::sim::Motion;
use crate::model::{Range, Spelling};

use super::mock_profile::ProfileName;

/// A value type a setting may have.
pub trait SettingValue {
    /// The TOML value of a flag's `text`, or why it is none.
    fn parse(text: &str) -> Result<toml::Value, String>;

    /// Its accepted names and what each means; empty for an open type (a number, a path).
    fn choices() -> &'static [(&'static str, &'static str)] {
        &[]
    }
}

/// A closed set of values, each with the name the flag, the TOML file and `campaign.json` spell it (its serde
/// name, which a test checks) and what it means.
pub trait Choice: Sized + Copy + PartialEq + 'static {
    /// Every value with its name and meaning, in the order `--help` lists them.
    const ALL: &'static [(Self, &'static str, &'static str)];

    /// The value's name.
    fn name(self) -> &'static str {
        Self::ALL.iter().find(|(v, ..)| *v == self).map_or("", |(_, n, _)| n)
    }

    /// The value called `name`.
    fn named(name: &str) -> Option<Self> {
        Self::ALL.iter().find(|(_, n, _)| *n == name).map(|(v, ..)| *v)
    }

    /// Every name and meaning.
    fn names() -> &'static [(&'static str, &'static str)];
}

/// Declares the values of a [`Choice`] and makes it a [`SettingValue`].
macro_rules! choice {
    ($ty:ty { $( $value:expr => $name:literal : $doc:literal ),* $(,)? }) => {
        impl Choice for $ty {
            const ALL: &'static [(Self, &'static str, &'static str)] = &[ $( ($value, $name, $doc) ),* ];
            fn names() -> &'static [(&'static str, &'static str)] {
                &[ $( ($name, $doc) ),* ]
            }
        }
        impl SettingValue for $ty {
            fn parse(text: &str) -> Result<toml::Value, String> {
                let text = text.trim();
                match <$ty as Choice>::named(text) {
                    Some(_) => Ok(toml::Value::String(text.to_string())),
                    None => Err(format!(
                        "{text:?} is not one of {}",
                        <$ty as Choice>::names().iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                    )),
                }
            }
            fn choices() -> &'static [(&'static str, &'static str)] {
                <$ty as Choice>::names()
            }
        }
    };
}

choice!(FlyMode {
    FlyMode::Avoidance => "avoidance": "PX4 <= 1.15 flies the mission with COM_OBS_AVOID = 1; prgenuav is its avoidance companion.",
    FlyMode::Offboard => "offboard": "prgenuav flies the waypoints in OFFBOARD mode with the planner's setpoints (any PX4).",
    FlyMode::Mission => "mission": "PX4 flies the plain mission, no avoidance (the baseline).",
    FlyMode::CollisionPrevention => "collision-prevention": "PX4's Collision Prevention is tested: prgenuav flies Position mode as a pilot and feeds a virtual lidar.",
});

choice!(VehicleSim {
    VehicleSim::Sih => "sih": "PX4's own SIH quadrotor inside PX4 SITL (v1.14 on).",
    VehicleSim::Iris => "iris": "prgenuav's iris simulator in this process, PX4 SITL in external-simulator mode (v1.12 on).",
});

choice!(Bench {
    Bench::Plain => "plain": "The build, --sim and the test's parameters as given.",
    Bench::Competition => "competition": "The competition's simulator as reproduced here: PX4 v1.12, the iris facing East, MPC_XY_CRUISE 2.3 (cross-validated).",
});

choice!(SimLink {
    SimLink::Tcp => "tcp": "PX4's TCP connection to the simulator, in lockstep.",
    SimLink::Serial => "serial": "A serial pty joined to PX4's TCP port by socat, on the wall clock (as a board).",
});

choice!(Motion {
    Motion::Px4 => "px4": "PX4's waypoint generator and a PX4-like position tracker.",
    Motion::Paper => "paper": "The paper's kinematic rule towards the planner's first tree node.",
});

choice!(Judge {
    Judge::E2026 => "2026": "From the path buffered by half the vehicle width, horizontally (the current edition).",
    Judge::E2025 => "2025": "From the bare path, with the height-gap rule when the path passes over a box.",
});

choice!(Spelling {
    Spelling::New => "new": "`robot:` and `mission:` (Aerialist since 2025-09).",
    Spelling::Old => "old": "`drone:` and `test:` (Aerialist before 2025-09, e.g. the 2025 competition's).",
});

choice!(Family {
    Family::Paper => "paper": "The paper's two-obstacle S.",
    Family::Extended => "extended": "The split drawn too, and a third obstacle where the case allows.",
    Family::Gate => "gate": "Two boxes across the path with a gap around 2 x CP_DIST.",
});

choice!(ProfileName {
    ProfileName::Px4Sitl => "px4-sitl": "Fitted to real PX4 v1.14 SITL (SIH), with its flight-to-flight scatter.",
    ProfileName::Competition => "competition": "Fitted to the competition's recorded Gazebo flights, without gusts.",
});

impl SettingValue for f64 {
    fn parse(text: &str) -> Result<toml::Value, String> {
        let v: f64 = text.trim().parse().map_err(|_| format!("{text:?} is not a number"))?;
        Ok(toml::Value::Float(v))
    }
}

impl SettingValue for usize {
    fn parse(text: &str) -> Result<toml::Value, String> {
        let v: i64 = text
            .trim()
            .parse()
            .map_err(|_| format!("{text:?} is not a whole number"))?;
        if v < 0 {
            return Err(format!("{text:?} is negative"));
        }
        Ok(toml::Value::Integer(v))
    }
}

impl SettingValue for u32 {
    fn parse(text: &str) -> Result<toml::Value, String> {
        <usize as SettingValue>::parse(text)
    }
}

impl SettingValue for u64 {
    fn parse(text: &str) -> Result<toml::Value, String> {
        // TOML integers are signed 64-bit: a seed beyond that is spelled as text and read back by serde.
        let v: u64 = text
            .trim()
            .parse()
            .map_err(|_| format!("{text:?} is not a whole number of 0 or more"))?;
        Ok(i64::try_from(v).map_or_else(|_| toml::Value::String(v.to_string()), toml::Value::Integer))
    }
}

impl SettingValue for bool {
    fn parse(text: &str) -> Result<toml::Value, String> {
        text.trim()
            .parse()
            .map(toml::Value::Boolean)
            .map_err(|_| format!("{text:?} is not true or false"))
    }
}

impl SettingValue for String {
    fn parse(text: &str) -> Result<toml::Value, String> {
        Ok(toml::Value::String(text.to_string()))
    }
}

impl SettingValue for PathBuf {
    fn parse(text: &str) -> Result<toml::Value, String> {
        Ok(toml::Value::String(text.to_string()))
    }
}

impl SettingValue for Range {
    fn parse(text: &str) -> Result<toml::Value, String> {
        let r = parse_range(text)?;
        let mut t = toml::Table::new();
        t.insert("min".into(), toml::Value::Float(r.min));
        t.insert("max".into(), toml::Value::Float(r.max));
        Ok(toml::Value::Table(t))
    }
}

/// A comma-separated list (`--connect udpin:a,udpin:b`), blanks dropped.
impl SettingValue for Vec<String> {
    fn parse(text: &str) -> Result<toml::Value, String> {
        Ok(toml::Value::Array(
            text.split(',')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(|s| toml::Value::String(s.to_string()))
                .collect(),
        ))
    }
}

/// `--diagonal 6,11` and the like: a range as `MIN,MAX`.
pub fn parse_range(s: &str) -> Result<Range, String> {
    let (a, b) = s.split_once(',').ok_or_else(|| format!("{s:?}: expected MIN,MAX"))?;
    let num = |t: &str| t.trim().parse::<f64>().map_err(|_| format!("{t:?} is not a number"));
    Ok(Range::new(num(a)?, num(b)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Serialize;
    use serde::de::DeserializeOwned;

    /// Each name is the value's serde name, so the flag, the TOML file and campaign.json agree.
    fn names_are_serde_names<T: Choice + Serialize + DeserializeOwned + std::fmt::Debug>() {
        for (v, name, doc) in T::ALL {
            assert_eq!(serde_json::to_value(v).unwrap(), serde_json::json!(name), "{v:?}");
            assert_eq!(serde_json::from_value::<T>(serde_json::json!(name)).unwrap(), *v);
            assert_eq!(T::named(name), Some(*v));
            assert_eq!(v.name(), *name);
            assert!(!doc.is_empty());
        }
    }

    #[test]
    fn every_choice_is_spelled_as_serde_spells_it() {
        names_are_serde_names::<FlyMode>();
        names_are_serde_names::<Motion>();
        names_are_serde_names::<Judge>();
        names_are_serde_names::<Spelling>();
        names_are_serde_names::<Family>();
        names_are_serde_names::<ProfileName>();
        names_are_serde_names::<VehicleSim>();
        names_are_serde_names::<SimLink>();
    }

    #[test]
    fn a_flag_outside_its_choices_names_them() {
        let e = <FlyMode as SettingValue>::parse("ofboard").unwrap_err();
        assert!(e.contains("avoidance, offboard, mission, collision-prevention"), "{e}");
        assert_eq!(
            <FlyMode as SettingValue>::parse("offboard"),
            Ok(toml::Value::String("offboard".into()))
        );
    }

    #[test]
    fn numbers_and_lists_read_as_typed() {
        assert_eq!(<u64 as SettingValue>::parse("7"), Ok(toml::Value::Integer(7)));
        assert_eq!(
            <u64 as SettingValue>::parse(&u64::MAX.to_string()),
            Ok(toml::Value::String(u64::MAX.to_string()))
        );
        assert!(<u64 as SettingValue>::parse("-1").is_err());
        assert!(<usize as SettingValue>::parse("-1").unwrap_err().contains("negative"));
        let list = <Vec<String> as SettingValue>::parse(" a, ,b ").unwrap();
        assert_eq!(list, toml::Value::Array(vec!["a".into(), "b".into()]));
    }
}
