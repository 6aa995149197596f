//! Which PX4 release a vehicle or a build runs, and what that release can do: the per-release capability
//! table every version-dependent choice reads (SIH and its home variables, the external-simulator start-up, the avoidance interface, Collision
//! Prevention, the modes that fly). A release not in the table is refused by name, never guessed.

use super::options::{FlyMode, VehicleSim};

/// A PX4 version as its git tag (`v1.16.2`, `v1.14.0-beta2-325-g1555f2bd22`) or AUTOPILOT_VERSION says.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Px4Version {
    /// Major number (1).
    pub major: u32,
    /// Minor number (14 ... 17).
    pub minor: u32,
    /// Patch number.
    pub patch: u32,
    /// The text it was read from (a tag, or `1.16.2` for AUTOPILOT_VERSION).
    pub text: String,
}

impl std::fmt::Display for Px4Version {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

impl Px4Version {
    /// Reads a git tag or version text: an optional `v`, then `MAJOR.MINOR.PATCH`, then anything (`-rc1`,
    /// `-beta2-325-g...`). None when it does not start that way.
    pub fn parse(text: &str) -> Option<Px4Version> {
        let t = text.trim();
        let digits = t.strip_prefix('v').unwrap_or(t);
        let mut parts = digits.splitn(3, '.');
        let major = parts.next()?.parse().ok()?;
        let minor = parts.next()?.parse().ok()?;
        let rest = parts.next()?;
        let end = rest.find(|c: char| !c.is_ascii_digit()).unwrap_or(rest.len());
        let patch = rest[..end].parse().ok()?;
        Some(Px4Version {
            major,
            minor,
            patch,
            text: t.to_string(),
        })
    }

    /// MAVLink's AUTOPILOT_VERSION.flight_sw_version (major, minor, patch in the top three bytes). None for 0,
    /// which a build without a version tag reports.
    pub fn from_flight_sw(v: u32) -> Option<Px4Version> {
        let (major, minor, patch) = (v >> 24, (v >> 16) & 0xff, (v >> 8) & 0xff);
        (major != 0 || minor != 0).then(|| Px4Version {
            major,
            minor,
            patch,
            text: format!("{major}.{minor}.{patch}"),
        })
    }

    /// The release's row of [`RELEASES`], or why not.
    pub fn release(&self) -> Result<&'static Release, UncheckedRelease> {
        RELEASES
            .iter()
            .find(|r| r.major == self.major && r.minor == self.minor)
            .ok_or_else(|| UncheckedRelease { read: self.clone() })
    }
}

/// How SIH takes its home from `PX4_HOME_LAT` / `PX4_HOME_LON` / `PX4_HOME_ALT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HomeUnits {
    /// INT32 `SIH_LOC_LAT0/LON0` in 1e-7 degrees; `PX4_HOME_ALT` ignored (v1.14, v1.15).
    IntE7,
    /// FLOAT `SIH_LOC_LAT0/LON0` in degrees; `PX4_HOME_ALT` sets `SIH_LOC_H0`, metres AMSL (v1.16 on).
    FloatDegrees,
}

/// How a row of the table was established.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Checked {
    /// Flown: the conformance tests ran on a build of this release.
    Flown,
    /// Read from this release's sources only.
    Source,
    /// Not possible on this release.
    Absent,
}

/// How PX4 SITL of a release runs with an external simulator (`simulator_mavlink`; v1.12's `simulator`):
/// the quadrotor airframe that has no simulator of its own, and what a build that can do it contains.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExternalSim {
    /// `PX4_SIM_MODEL` (with `PX4_SIMULATOR` unset): `none_iris` from v1.14, `iris` in v1.12.
    pub model: &'static str,
    /// The startup script given with `-s`, relative to the build's `etc` (v1.12's default is NuttX's rcS).
    pub startup: Option<&'static str>,
    /// The module's command in `BUILD/bin`: a build without it cannot feed PX4 from outside.
    pub module: &'static str,
}

/// v1.14 and later: `none_iris` (airframe 10016), `simulator_mavlink start -c 4560+i`.
const NONE_IRIS: ExternalSim = ExternalSim {
    model: "none_iris",
    startup: None,
    module: "px4-simulator_mavlink",
};

/// What one PX4 major.minor release can do.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Release {
    /// Major number.
    pub major: u32,
    /// Minor number.
    pub minor: u32,
    /// SIH in SITL and how it reads its home; `None`: no SIH in SITL (v1.12 comments it out of the board).
    pub sih: Option<HomeUnits>,
    /// The external-simulator start-up (`--sim iris`).
    pub external: ExternalSim,
    /// The obstacle-avoidance interface (`COM_OBS_AVOID`, `TRAJECTORY_REPRESENTATION_WAYPOINTS`).
    pub avoidance_interface: bool,
    /// Collision Prevention (`CP_DIST`, fed by `OBSTACLE_DISTANCE`, acting in Position mode).
    pub collision_prevention: bool,
    /// The `MPC_POS_MODE` values in which that Collision Prevention acts, the one to set first: up to v1.15
    /// only the velocity-based Position modes call it (0 direct, 3 smoothed; not PX4's default 4), from
    /// v1.16 only the acceleration-based one (4).
    pub cp_position_modes: &'static [u8],
    /// How this row was established with SIH (`--sim sih`).
    pub checked: Checked,
    /// How it was established with prgenuav's iris simulator (`--sim iris`).
    pub checked_iris: Checked,
}

/// Every release prgenuav has checked, oldest first.
pub const RELEASES: [Release; 5] = [
    Release {
        major: 1,
        minor: 12,
        sih: None,
        external: ExternalSim {
            model: "iris",
            startup: Some("etc/init.d-posix/rcS"),
            module: "px4-simulator",
        },
        avoidance_interface: true,
        collision_prevention: true,
        cp_position_modes: &[3, 0],
        checked: Checked::Absent,
        checked_iris: Checked::Flown,
    },
    Release {
        major: 1,
        minor: 14,
        sih: Some(HomeUnits::IntE7),
        external: NONE_IRIS,
        avoidance_interface: true,
        collision_prevention: true,
        cp_position_modes: &[3, 0],
        checked: Checked::Flown,
        checked_iris: Checked::Flown,
    },
    Release {
        major: 1,
        minor: 15,
        sih: Some(HomeUnits::IntE7),
        external: NONE_IRIS,
        avoidance_interface: true,
        collision_prevention: true,
        cp_position_modes: &[3, 0],
        checked: Checked::Source,
        checked_iris: Checked::Source,
    },
    Release {
        major: 1,
        minor: 16,
        sih: Some(HomeUnits::FloatDegrees),
        external: NONE_IRIS,
        avoidance_interface: false,
        collision_prevention: true,
        cp_position_modes: &[4],
        checked: Checked::Flown,
        checked_iris: Checked::Flown,
    },
    Release {
        major: 1,
        minor: 17,
        sih: Some(HomeUnits::FloatDegrees),
        external: NONE_IRIS,
        avoidance_interface: false,
        collision_prevention: true,
        cp_position_modes: &[4],
        checked: Checked::Source,
        checked_iris: Checked::Source,
    },
];

/// Case-study parameters only the avoidance interface reads: on a PX4 without that interface they are
/// skipped with a warning (other parameters the vehicle lacks stop the flight, naming them).
pub const AVOIDANCE_ONLY_PARAMS: [&str; 1] = ["COM_OBS_AVOID"];

impl Release {
    /// Whether `mode` can fly on this release.
    pub fn supports(&self, mode: FlyMode) -> bool {
        match mode {
            FlyMode::Avoidance => self.avoidance_interface,
            FlyMode::Offboard | FlyMode::Mission => true,
            FlyMode::CollisionPrevention => self.collision_prevention,
        }
    }

    /// Whether `sim` can feed this release's SITL; if not, the refusal (naming `version`).
    pub fn sim_refusal(&self, version: &Px4Version, sim: VehicleSim) -> Option<String> {
        match sim {
            VehicleSim::Sih if self.sih.is_none() => Some(format!(
                "--sim sih: PX4 {version} has no SIH in SITL (v1.{} leaves the SIH module out of its SITL build); \
                 fly it with prgenuav's simulator: --sim iris",
                self.minor
            )),
            _ => None,
        }
    }

    /// The modes that fly here, in words (`offboard, mission`).
    pub fn modes(&self) -> String {
        let all = [
            FlyMode::Avoidance,
            FlyMode::Offboard,
            FlyMode::Mission,
            FlyMode::CollisionPrevention,
        ];
        let names: Vec<String> = all.into_iter().filter(|m| self.supports(*m)).map(mode_name).collect();
        names.join(", ")
    }
}

/// The refusal of `mode` on `version` (whose release lacks it), naming what works there.
pub fn mode_refusal(version: &Px4Version, release: &Release, mode: FlyMode) -> String {
    let why = match mode {
        FlyMode::Avoidance => {
            " has no obstacle-avoidance interface (COM_OBS_AVOID; PX4 removed it in v1.16.0, so --mode avoidance \
             needs PX4 1.14 or 1.15)"
        }
        _ => " cannot fly it",
    };
    format!(
        "--mode {}: PX4 {version}{why}; modes that work on PX4 {}.{}: {}",
        mode_name(mode),
        release.major,
        release.minor,
        release.modes()
    )
}

/// A mode's name as the command line spells it.
fn mode_name(mode: FlyMode) -> String {
    serde_json::to_value(mode)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

/// A version whose major.minor is not in [`RELEASES`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("PX4 {read} (read as {}.{}) has not been checked with prgenuav; checked: {}", read.major, read.minor, checked_list())]
pub struct UncheckedRelease {
    /// What was read.
    pub read: Px4Version,
}

fn checked_list() -> String {
    let v: Vec<String> = RELEASES.iter().map(|r| format!("{}.{}", r.major, r.minor)).collect();
    v.join(", ")
}

#[cfg(test)]
#[path = "px4_version_tests.rs"]
mod tests;
