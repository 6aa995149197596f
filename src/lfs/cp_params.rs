//! PX4 Collision Prevention's parameters as a test sets them: from its parameter CSV, else our defaults.
//!
//! PX4 ships `CP_DIST = -1` (off). A Collision Prevention test needs it on, so the default here is 2 m:
//! above the competition's 1.5 m failure threshold, so a vehicle that keeps `CP_DIST` never fails, and a
//! failure means Collision Prevention let the vehicle through. The others keep PX4's defaults.

use crate::model::Param;

/// The four parameters (PX4 v1.14-v1.17 names and units).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CpParams {
    /// `CP_DIST`: the distance to keep, metres (> 0 enables Collision Prevention).
    pub dist_m: f64,
    /// `CP_DELAY`: the sensor and estimation delay assumed, seconds.
    pub delay_s: f64,
    /// `CP_GUIDE_ANG`: how far the stick direction may be bent toward a freer sector, degrees.
    pub guide_ang_deg: f64,
    /// `CP_GO_NO_DATA`: whether to move into sectors without data.
    pub go_no_data: bool,
}

/// Our `CP_DIST` when the test does not set it, metres.
pub const DEFAULT_CP_DIST_M: f64 = 2.0;

impl Default for CpParams {
    fn default() -> Self {
        Self {
            dist_m: DEFAULT_CP_DIST_M,
            delay_s: 0.4,
            guide_ang_deg: 30.0,
            go_no_data: false,
        }
    }
}

impl CpParams {
    /// The test's values where it sets them, the defaults elsewhere. A `CP_DIST` of 0 or below (off) is
    /// refused: the test would not test Collision Prevention.
    pub fn from_params(params: &[Param]) -> Result<Self, String> {
        let get = |name: &str| params.iter().rev().find(|p| p.name == name).map(|p| p.value);
        let d = Self::default();
        let out = Self {
            dist_m: get("CP_DIST").unwrap_or(d.dist_m),
            delay_s: get("CP_DELAY").unwrap_or(d.delay_s),
            guide_ang_deg: get("CP_GUIDE_ANG").unwrap_or(d.guide_ang_deg),
            go_no_data: get("CP_GO_NO_DATA").map_or(d.go_no_data, |v| v != 0.0),
        };
        let bad = |name: &str, v: f64, rule: &str| Err(format!("parameter {name} = {v}: {rule}"));
        if !(out.dist_m.is_finite() && out.dist_m > 0.0 && out.dist_m <= 15.0) {
            return bad(
                "CP_DIST",
                out.dist_m,
                "must be above 0 (Collision Prevention on) and at most 15 m",
            );
        }
        if !(0.0..=1.0).contains(&out.delay_s) {
            return bad("CP_DELAY", out.delay_s, "must be 0-1 s");
        }
        if !(0.0..=90.0).contains(&out.guide_ang_deg) {
            return bad("CP_GUIDE_ANG", out.guide_ang_deg, "must be 0-90 degrees");
        }
        Ok(out)
    }

    /// The parameters to set on the vehicle, as PX4 names them.
    pub fn to_params(&self) -> Vec<(String, f64)> {
        vec![
            ("CP_DIST".into(), self.dist_m),
            ("CP_DELAY".into(), self.delay_s),
            ("CP_GUIDE_ANG".into(), self.guide_ang_deg),
            ("CP_GO_NO_DATA".into(), f64::from(u8::from(self.go_no_data))),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(name: &str, value: f64) -> Param {
        Param {
            name: name.into(),
            value,
        }
    }

    #[test]
    fn the_test_overrides_the_defaults_and_nonsense_is_refused() {
        assert_eq!(CpParams::from_params(&[]).unwrap(), CpParams::default());
        let c = CpParams::from_params(&[p("CP_DIST", 3.0), p("CP_GO_NO_DATA", 1.0)]).unwrap();
        assert_eq!((c.dist_m, c.go_no_data, c.delay_s), (3.0, true, 0.4));
        assert_eq!(c.to_params()[3], ("CP_GO_NO_DATA".to_string(), 1.0));
        let e = CpParams::from_params(&[p("CP_DIST", -1.0)]).unwrap_err();
        assert!(e.contains("CP_DIST") && e.contains("above 0"), "{e}");
        assert!(
            CpParams::from_params(&[p("CP_DELAY", 2.0)])
                .unwrap_err()
                .contains("CP_DELAY")
        );
    }
}
