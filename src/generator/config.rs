//! The generator's parameters, with the paper's defaults, readable from TOML.

use serde::{Deserialize, Serialize};

use crate::model::{Limit, Range};

/// Which construction a generator draws from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// The paper's: five draws, `split` fixed, two obstacles.
    #[default]
    Paper,
    /// The split drawn too (`adapted_split`), and a third obstacle (`third_ahead_m`) where its draw and the
    /// case allow. Opt-in: on the embedded mock it found fewer failures (mission 2, seeds 0-2, adapted
    /// campaign: 25 against 42 for the paper's family).
    Extended,
    /// Two boxes across the path leaving a gap around 2 x `CP_DIST` ([`super::gate`]): the default with
    /// `--mode collision-prevention`.
    Gate,
}

/// Every knob of the two-obstacle construction (paper, section II). Lengths in metres, angles in degrees.
///
/// Obstacle 1's *A* end is the short part (`split` of its length) on one side of the segment of interest
/// (SoI), *B* the rest on the other side. Obstacle 2 stands beyond the A end, perpendicular to obstacle 1,
/// leaving a gap the drone must fly through: that is what forces the S-shaped path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GeneratorConfig {
    /// Diagonal of obstacle 1's base. The upper bound keeps obstacle 2 (1.75 x as long) within the 20 m rule.
    pub diagonal_m: Range,
    /// Width of both bases (the paper: 2 m).
    pub width_m: f64,
    /// Share of obstacle 1's length on the A side of the SoI (the paper: 1/3).
    pub split: f64,
    /// Obstacle 2's length as a multiple of obstacle 1's (the paper: 1.75), so the drone cannot circle it.
    pub length_factor: f64,
    /// Height of both boxes (the paper: 20 m, above the 10 m flight altitude so the drone cannot fly over).
    pub height_m: f64,
    /// Acute angle between obstacle 1's A direction and the SoI's direction of travel; the SoI meets the
    /// B part at the obtuse supplement (the paper's "obtuse angle").
    pub angle_deg: Range,
    /// Gap between obstacle 1's A end and obstacle 2. 2 m is the narrowest opening the planner's 6-degree,
    /// 40-degree-smoothed histogram still shows as free from a few metres away; at 4 m a drone flying the
    /// middle of the gap passes 2 m from each side, just outside the 1.5 m failure distance, so every gap in
    /// range can produce a failure once the drone's turn carries it off-centre.
    pub gap_m: Range,
    /// How far obstacle 2 reaches past obstacle 1's far (back) face, as a share of its length; the rest of it
    /// reaches back towards the approaching drone, which is what stops it circling obstacle 2 "from below".
    pub overhang: Range,
    /// The construction drawn: `paper` (default) or `extended` (the split drawn from `adapted_split`, and a
    /// third obstacle).
    pub family: Family,
    /// The extended family's range of `split` (the paper's family keeps `split`).
    pub adapted_split: Range,
    /// The extended family's third obstacle: the clear distance along the segment of interest between the
    /// pair's farthest point and the third obstacle's nearest one. It is obstacle 1 mirrored across the
    /// segment (same length, angle and split, its short part on the other side), so the drone flies a second,
    /// reversed S; where the case leaves no room for it on the segment, the draw is refused.
    pub third_ahead_m: Range,
    /// Attempts per test before the generator reports that the mission leaves no room.
    pub max_attempts: u32,
}

impl Default for GeneratorConfig {
    fn default() -> Self {
        Self {
            diagonal_m: Range::new(6.0, 11.6),
            width_m: 2.0,
            split: 1.0 / 3.0,
            length_factor: 1.75,
            height_m: 20.0,
            angle_deg: Range::new(20.0, 70.0),
            gap_m: Range::new(2.0, 4.0),
            overhang: Range::new(0.0, 1.0 / 3.0),
            family: Family::Paper,
            adapted_split: Range::new(0.2, 0.45),
            third_ahead_m: Range::new(2.0, 8.0),
            max_attempts: 10_000,
        }
    }
}

impl GeneratorConfig {
    /// Reads a TOML file; keys left out keep their defaults.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let c: Self = toml::from_str(text).map_err(|e| e.to_string())?;
        c.validate()?;
        Ok(c)
    }

    /// Checks that the numbers make a construction possible, naming the first one that does not.
    pub fn validate(&self) -> Result<(), String> {
        let range = |name: &str, r: Range, limit: Limit| -> Result<(), String> {
            if !(limit.holds(r.min) && limit.holds(r.max) && r.min <= r.max) {
                return Err(format!(
                    "{name}: [{}, {}] must be an ordered range within {}",
                    r.min,
                    r.max,
                    limit.range()
                ));
            }
            Ok(())
        };
        let number = |name: &str, v: f64, limit: Limit| limit.check(name, v).map(drop);
        number("width_m", self.width_m, limits::WIDTH_M)?;
        range("diagonal_m", self.diagonal_m, limits::DIAGONAL_M)?;
        if self.diagonal_m.min < self.width_m * 1.0001 {
            return Err(format!(
                "diagonal_m: {} must be longer than width_m {}",
                self.diagonal_m.min, self.width_m
            ));
        }
        range("angle_deg", self.angle_deg, limits::ANGLE_DEG)?;
        range("gap_m", self.gap_m, limits::GAP_M)?;
        range("overhang", self.overhang, limits::OVERHANG)?;
        range("adapted_split", self.adapted_split, limits::ADAPTED_SPLIT)?;
        range("third_ahead_m", self.third_ahead_m, limits::THIRD_AHEAD_M)?;
        number("split", self.split, limits::SPLIT)?;
        number("length_factor", self.length_factor, limits::LENGTH_FACTOR)?;
        number("height_m", self.height_m, limits::HEIGHT_M)?;
        number("max_attempts", f64::from(self.max_attempts), limits::MAX_ATTEMPTS)?;
        Ok(())
    }
}

/// Each number's accepted values; a range's two ends both lie within its key's.
pub mod limits {
    use crate::model::Limit;

    /// Diagonal of obstacle 1's base.
    pub const DIAGONAL_M: Limit = Limit::above(0.0, 1e3, "m");
    /// Width of both bases.
    pub const WIDTH_M: Limit = Limit::above(0.0, 100.0, "m");
    /// The A side is the shorter part of obstacle 1.
    pub const SPLIT: Limit = Limit::between(0.0, 0.5, "");
    /// At least 1: obstacle 2 is never shorter than obstacle 1.
    pub const LENGTH_FACTOR: Limit = Limit::within(1.0, 100.0, "");
    /// Height of both boxes.
    pub const HEIGHT_M: Limit = Limit::above(0.0, 1e3, "m");
    /// Angle of obstacle 1 to the direction of flight.
    pub const ANGLE_DEG: Limit = Limit::within(1.0, 89.0, "deg");
    /// Gap between the obstacles.
    pub const GAP_M: Limit = Limit::within(0.01, 100.0, "m");
    /// Obstacle 2's reach past obstacle 1, a share of its length.
    pub const OVERHANG: Limit = Limit::within(0.0, 1.0, "");
    /// The extended family's split.
    pub const ADAPTED_SPLIT: Limit = Limit::within(0.01, 0.49, "");
    /// The extended family's distance to the third obstacle.
    pub const THIRD_AHEAD_M: Limit = Limit::within(0.5, 100.0, "m");
    /// Draws per test.
    pub const MAX_ATTEMPTS: Limit = Limit::count(1, 10_000_000, "draws");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_toml_overrides_some_keys() {
        GeneratorConfig::default().validate().unwrap();
        let c = GeneratorConfig::from_toml("gap_m = { min = 2.5, max = 3.0 }\nheight_m = 15.0\n").unwrap();
        assert_eq!(c.gap_m, Range::new(2.5, 3.0));
        assert_eq!(c.height_m, 15.0);
        assert_eq!(c.split, 1.0 / 3.0);
        assert_eq!(c.family, Family::Paper);
        assert_eq!(
            GeneratorConfig::from_toml("family = \"extended\"").unwrap().family,
            Family::Extended
        );
        assert!(
            GeneratorConfig::from_toml("family = \"wide\"")
                .unwrap_err()
                .contains("family")
        );
        assert!(
            GeneratorConfig::from_toml("gap = 1")
                .unwrap_err()
                .contains("unknown field")
        );
        assert!(GeneratorConfig::from_toml("split = 0.7").unwrap_err().contains("split"));
        let e = GeneratorConfig::from_toml("adapted_split = { min = 0.3, max = 0.6 }").unwrap_err();
        assert!(e.contains("adapted_split"), "{e}");
        let e = GeneratorConfig::from_toml("third_ahead_m = { min = 5.0, max = 3.0 }").unwrap_err();
        assert!(e.contains("third_ahead_m"), "{e}");
    }
}
