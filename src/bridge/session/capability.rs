//! What the vehicle's PX4 release can fly, decided before anything is set, uploaded or armed: a release
//! prgenuav has not checked is refused by name, a mode the release lacks is refused naming the modes that
//! work there, and case-study parameters only the avoidance interface reads are skipped with a warning on a
//! PX4 without that interface (any other parameter the vehicle lacks stops the flight, naming it).

use super::context::{Session, Stop};
use super::report::Status;
use crate::bridge::options::FlyMode;
use crate::bridge::px4_version::{AVOIDANCE_ONLY_PARAMS, Release, mode_refusal};

/// The parameter switching PX4's avoidance interface on.
pub const AVOIDANCE_SWITCH: &str = "COM_OBS_AVOID";

impl Session<'_> {
    /// The vehicle's release, when it reported one; refuses an unchecked release and a mode it cannot fly.
    pub fn check_release(&self) -> Result<Option<&'static Release>, Stop> {
        let Some(version) = &self.px4_version else {
            return Ok(None);
        };
        let release = version.release().map_err(|e| {
            Stop::new(
                Status::Rejected,
                format!("the vehicle reports {e} (AUTOPILOT_VERSION.flight_sw_version)"),
            )
        })?;
        if !release.supports(self.opts.mode) {
            return Err(Stop::new(
                Status::Rejected,
                mode_refusal(version, release, self.opts.mode),
            ));
        }
        Ok(Some(release))
    }

    /// The refusal of avoidance mode on a vehicle found to lack [`AVOIDANCE_SWITCH`] (its release unknown).
    pub fn no_avoidance_interface(&self) -> Stop {
        let version = self.px4_version.as_ref().map_or_else(
            || "this vehicle (its version not reported)".to_string(),
            |v| format!("PX4 {v}"),
        );
        Stop::new(
            Status::Rejected,
            format!(
                "--mode avoidance: {version} has no parameter {AVOIDANCE_SWITCH}, so no obstacle-avoidance \
                 interface (PX4 removed it in v1.16.0); fly --mode offboard or --mode mission"
            ),
        )
    }
}

/// The parameters to set, in order: the case study's, then [`AVOIDANCE_SWITCH`] for `mode` (first in
/// avoidance mode, so a vehicle without it refuses before anything else changes). With `interface`
/// `Some(false)` the avoidance-only parameters are left out; their names come back to be warned about.
pub fn wanted_params(
    case: &[(String, f64)],
    mode: FlyMode,
    interface: Option<bool>,
) -> (Vec<(String, f64)>, Vec<String>) {
    let avoidance_only = |name: &str| AVOIDANCE_ONLY_PARAMS.contains(&name);
    let mut wanted: Vec<(String, f64)> = case
        .iter()
        .filter(|(name, _)| name != AVOIDANCE_SWITCH && (interface != Some(false) || !avoidance_only(name)))
        .cloned()
        .collect();
    let skipped: Vec<String> = case
        .iter()
        .filter(|(name, _)| interface == Some(false) && avoidance_only(name))
        .map(|(name, _)| name.clone())
        .collect();
    match (mode, interface) {
        (_, Some(false)) => {}
        (FlyMode::Avoidance, _) => wanted.insert(0, (AVOIDANCE_SWITCH.into(), 1.0)),
        _ => wanted.push((AVOIDANCE_SWITCH.into(), 0.0)),
    }
    (wanted, skipped)
}

/// The warning for case-study parameters skipped on a PX4 without the avoidance interface.
pub fn skipped_warning(skipped: &[String], version: Option<&str>) -> String {
    format!(
        "case-study parameter {} not set: {} has no obstacle-avoidance interface, the only reader of {}",
        skipped.join(", "),
        version.map_or_else(|| "this vehicle".to_string(), |v| format!("PX4 {v}")),
        if skipped.len() == 1 { "it" } else { "them" }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case() -> Vec<(String, f64)> {
        vec![
            ("MPC_XY_VEL_MAX".into(), 3.0),
            ("COM_OBS_AVOID".into(), 1.0),
            ("CP_DIST".into(), 2.0),
        ]
    }

    fn names(w: &[(String, f64)]) -> Vec<&str> {
        w.iter().map(|(n, _)| n.as_str()).collect()
    }

    #[test]
    fn the_avoidance_switch_follows_the_mode_on_a_px4_with_the_interface() {
        for interface in [Some(true), None] {
            let (w, skipped) = wanted_params(&case(), FlyMode::Avoidance, interface);
            assert_eq!(names(&w), ["COM_OBS_AVOID", "MPC_XY_VEL_MAX", "CP_DIST"]);
            assert_eq!((w[0].1, skipped.len()), (1.0, 0));
            let (w, _) = wanted_params(&case(), FlyMode::Offboard, interface);
            assert_eq!(names(&w), ["MPC_XY_VEL_MAX", "CP_DIST", "COM_OBS_AVOID"]);
            assert_eq!(w[2].1, 0.0);
        }
    }

    #[test]
    fn without_the_interface_only_the_avoidance_parameters_are_skipped_and_named() {
        let (w, skipped) = wanted_params(&case(), FlyMode::Mission, Some(false));
        assert_eq!(names(&w), ["MPC_XY_VEL_MAX", "CP_DIST"]);
        assert_eq!(skipped, ["COM_OBS_AVOID"]);
        let msg = skipped_warning(&skipped, Some("1.16.2"));
        assert_eq!(
            msg,
            "case-study parameter COM_OBS_AVOID not set: PX4 1.16.2 has no obstacle-avoidance interface, \
             the only reader of it"
        );
        let (_, none) = wanted_params(&case()[..1], FlyMode::Offboard, Some(false));
        assert!(none.is_empty());
    }
}
