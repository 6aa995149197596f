//! An adaptable distribution over the generator's unit draws: the paper's five (obstacle 1's diagonal, its
//! place along the segment of interest, the angle, the gap, obstacle 2's overhang) and, in the extended family
//! only, three more (the split of obstacle 1 across the segment, whether a third obstacle stands beyond the
//! pair, and how far beyond). The paper's construction stays the family; only where in its ranges the draws
//! fall changes.
//!
//! Each draw has its own histogram density on [0, 1] with [`BINS`] equal bins (a univariate marginal
//! distribution algorithm, UMDA, with histogram marginals, the estimation-of-distribution relative of the
//! cross-entropy method). A draw maps a uniform number through the histogram's inverse CDF, so a test still
//! takes exactly one random number per draw and depends only on the seed, its index and the distribution.
//! [`DrawDistribution::fitted`] moves each histogram towards the draws of the best candidates; a floor of
//! uniform mass keeps every part of every range reachable (and the suite diverse).

use serde::{Deserialize, Serialize};

/// Draws of the paper's generator (the static family takes only these, so its tests stay as they were).
pub const PAPER_DIMS: usize = 5;
/// Draws of the extended family ([`crate::generator::Family::Extended`]): the paper's, then the split, the
/// third obstacle and its distance beyond the pair.
pub const DIMS: usize = 8;
/// Index of the split draw.
pub const SPLIT: usize = 5;
/// Index of the third obstacle's draw: below [`THIRD_FROM`], no third obstacle.
pub const THIRD: usize = 6;
/// Index of the draw of the third obstacle's distance beyond the pair.
pub const THIRD_AHEAD: usize = 7;
/// A third obstacle stands where its draw is at least this: 40 % of a uniform draw, and the draw's first three
/// fifths (the report's failure table) and first six bins mean "two obstacles".
pub const THIRD_FROM: f64 = 0.6;
/// Bins per draw.
pub const BINS: usize = 10;
/// Names of the draws, in order (for reports).
pub const DRAW_NAMES: [&str; DIMS] = [
    "diagonal",
    "position",
    "angle",
    "gap",
    "overhang",
    "split",
    "third",
    "third_ahead",
];

/// Histogram densities of the draws; each row holds bin probabilities summing to 1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DrawDistribution {
    /// `weights[d][k]`: probability that draw `d` falls in `[k / BINS, (k + 1) / BINS)`. A prior written
    /// before the extended family had its three extra draws (five rows) reads with those rows uniform.
    #[serde(deserialize_with = "padded_rows")]
    pub weights: [[f64; BINS]; DIMS],
}

/// Reads 1 to [`DIMS`] rows; missing rows are uniform.
fn padded_rows<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[[f64; BINS]; DIMS], D::Error> {
    padded(d, [1.0 / BINS as f64; BINS])
}

/// Reads one value per draw, 1 to [`DIMS`] of them (a file of the
/// paper's family may hold only its [`PAPER_DIMS`]); the missing ones are `fill`.
pub fn padded<'de, D: serde::Deserializer<'de>, T: Deserialize<'de> + Copy>(
    d: D,
    fill: T,
) -> Result<[T; DIMS], D::Error> {
    let rows: Vec<T> = Deserialize::deserialize(d)?;
    if rows.is_empty() || rows.len() > DIMS {
        return Err(serde::de::Error::custom(format!(
            "{} values, one per draw expected (1 to {DIMS})",
            rows.len()
        )));
    }
    let mut out = [fill; DIMS];
    out[..rows.len()].copy_from_slice(&rows);
    Ok(out)
}

impl Default for DrawDistribution {
    fn default() -> Self {
        Self::uniform()
    }
}

impl DrawDistribution {
    /// The paper's generator: every draw uniform.
    pub fn uniform() -> Self {
        Self {
            weights: [[1.0 / BINS as f64; BINS]; DIMS],
        }
    }

    /// Whether every draw is uniform (draws then pass through unchanged, bit for bit).
    pub fn is_uniform(&self) -> bool {
        self.weights
            .iter()
            .all(|row| row.iter().all(|w| (w - 1.0 / BINS as f64).abs() < 1e-12))
    }

    /// Refuses rows that are not probability vectors (a hand-edited prior file), naming the draw.
    pub fn validate(&self) -> Result<(), String> {
        for (d, row) in self.weights.iter().enumerate() {
            let sum: f64 = row.iter().sum();
            if row.iter().any(|w| !w.is_finite() || *w < 0.0) || (sum - 1.0).abs() > 1e-6 {
                return Err(format!(
                    "weights of draw {} ({}) must be non-negative and sum to 1 (they sum to {sum})",
                    d, DRAW_NAMES[d]
                ));
            }
        }
        Ok(())
    }

    /// Maps a uniform `u` in [0, 1) to draw `dim` (the inverse CDF of its histogram).
    pub fn map(&self, dim: usize, u: f64) -> f64 {
        if self.weights[dim].iter().all(|w| (w - 1.0 / BINS as f64).abs() < 1e-12) {
            return u;
        }
        let mut below = 0.0;
        for (k, w) in self.weights[dim].iter().enumerate() {
            if *w > 0.0 && (u < below + w || k == BINS - 1) {
                let within = ((u - below) / w).clamp(0.0, 1.0);
                return ((k as f64 + within) / BINS as f64).min(1.0 - f64::EPSILON);
            }
            below += w;
        }
        u
    }

    /// The distribution moved towards `elites` (draws in [0, 1], each with a weight): each row becomes
    /// `(1 - rate) * old + rate * histogram(elites)`, then mixed with `floor` of uniform mass.
    pub fn fitted(&self, elites: &[([f64; DIMS], f64)], rate: f64, floor: f64) -> Self {
        let total: f64 = elites.iter().map(|(_, w)| w.max(0.0)).sum();
        if total <= 0.0 {
            return self.clone();
        }
        let mut out = self.clone();
        for d in 0..DIMS {
            let mut hist = [0.0; BINS];
            for (x, w) in elites {
                let k = bin_of(x[d], BINS);
                hist[k] += w.max(0.0) / total;
            }
            for (k, h) in hist.iter().enumerate() {
                let moved = (1.0 - rate) * self.weights[d][k] + rate * h;
                out.weights[d][k] = (1.0 - floor) * moved + floor / BINS as f64;
            }
        }
        out
    }

    /// Mean of draw `dim` (for reports).
    pub fn mean(&self, dim: usize) -> f64 {
        self.weights[dim]
            .iter()
            .enumerate()
            .map(|(k, w)| w * (k as f64 + 0.5) / BINS as f64)
            .sum()
    }
}

/// A box of side `2 half_width` around one test's draws (a *neighbour* proposal): draw `d` becomes
/// `centre[d] + half_width (2u - 1)`, reflected at 0 and 1 so the box stays uniform near a border.
///
/// Why: on the embedded mock the flown distance of a test's nearest neighbour in draw space correlates with its
/// own at 0.68 (2147 distinct mission-2 flights), better than the LFS ranks flights (Spearman 0.31), so the
/// draws next to a flown failure are where the next failures are likeliest.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Neighbourhood {
    /// The parent test's unit draws.
    pub centre: [f64; DIMS],
    /// Half the box's side, in unit draws.
    pub half_width: f64,
}

impl Neighbourhood {
    /// Maps a uniform `u` in [0, 1) to draw `dim` near the centre, in [0, 1).
    pub fn map(&self, dim: usize, u: f64) -> f64 {
        let x = self.centre[dim] + self.half_width * (2.0 * u - 1.0);
        let reflected = if x < 0.0 {
            -x
        } else if x >= 1.0 {
            2.0 - x
        } else {
            x
        };
        reflected.clamp(0.0, 1.0 - f64::EPSILON)
    }
}

/// Where a generator's draws come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Proposal {
    /// Independent histogram marginals (uniform: the paper's generator).
    Histogram(Box<DrawDistribution>),
    /// Near a flown test.
    Around(Neighbourhood),
}

impl Proposal {
    /// Maps a uniform `u` in [0, 1) to draw `dim`.
    pub fn map(&self, dim: usize, u: f64) -> f64 {
        match self {
            Proposal::Histogram(d) => d.map(dim, u),
            Proposal::Around(n) => n.map(dim, u),
        }
    }
}

/// The bin of `u` (clamped to [0, 1]) among `bins` equal bins; 1.0 falls in the last.
pub fn bin_of(u: f64, bins: usize) -> usize {
    ((u.clamp(0.0, 1.0) * bins as f64) as usize).min(bins.saturating_sub(1))
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn uniform_passes_draws_through_bit_for_bit() {
        let d = DrawDistribution::uniform();
        assert!(d.is_uniform());
        for u in [0.0, 0.123_456_789, 0.5, 0.999_999] {
            assert_eq!(d.map(2, u).to_bits(), u.to_bits());
        }
    }

    #[test]
    fn fitting_moves_mass_towards_the_elites_and_keeps_the_floor() {
        let d = DrawDistribution::uniform();
        let elites = vec![([0.05, 0.95, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5], 1.0); 4];
        let f = d.fitted(&elites, 1.0, 0.1);
        f.validate().unwrap();
        // All the elite mass in bin 0 of draw 0, plus the floor's share.
        assert!((f.weights[0][0] - (0.9 + 0.01)).abs() < 1e-12, "{:?}", f.weights[0]);
        assert!((f.weights[0][5] - 0.01).abs() < 1e-12);
        assert!(f.mean(0) < 0.2 && f.mean(1) > 0.8);
        // After the fit, draws land mostly in the elite bin.
        let low = (0..1000).filter(|i| f.map(0, *i as f64 / 1000.0) < 0.1).count();
        assert!((900..=920).contains(&low), "{low}");
        // No elites, no change.
        assert_eq!(d.fitted(&[], 1.0, 0.1), d);
    }

    #[test]
    fn a_bad_prior_names_the_draw() {
        let mut d = DrawDistribution::uniform();
        d.weights[3][0] = 0.5;
        assert!(d.validate().unwrap_err().contains("gap"));
    }

    #[test]
    fn a_prior_of_the_paper_family_reads_with_the_extra_draws_uniform() {
        let mut five = DrawDistribution::uniform();
        five.weights[2] = [0.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0, 0.0, 0.0];
        let json = serde_json::to_value(&five).unwrap();
        let rows: Vec<serde_json::Value> = json["weights"].as_array().unwrap()[..PAPER_DIMS].to_vec();
        let old = serde_json::json!({ "weights": rows });
        let read: DrawDistribution = serde_json::from_value(old).unwrap();
        assert_eq!(read, five, "rows 5-7 uniform, the five read as written");
        let none = serde_json::json!({ "weights": [] });
        assert!(serde_json::from_value::<DrawDistribution>(none).is_err());
    }

    #[test]
    fn a_neighbourhood_stays_near_its_centre_and_reflects_at_the_borders() {
        let n = Neighbourhood {
            centre: [0.5, 0.02, 0.99, 0.3, 0.7, 0.5, 0.5, 0.5],
            half_width: 0.1,
        };
        assert!((n.map(0, 0.0) - 0.4).abs() < 1e-12);
        assert!((n.map(0, 0.75) - 0.55).abs() < 1e-12);
        // 0.02 - 0.1 = -0.08 reflects to 0.08; 0.99 + 0.1 = 1.09 reflects to 0.91.
        assert!((n.map(1, 0.0) - 0.08).abs() < 1e-12);
        assert!((n.map(2, 1.0) - 0.91).abs() < 1e-12);
        let p = Proposal::Around(n);
        assert_eq!(p.map(3, 0.5), 0.3);
    }

    proptest! {
        #[test]
        fn neighbour_draws_stay_in_the_unit_interval_and_the_box(
            centre in proptest::array::uniform8(0.0f64..1.0),
            half_width in 0.0f64..0.5,
            u in 0.0f64..1.0,
            dim in 0usize..DIMS,
        ) {
            let n = Neighbourhood { centre, half_width };
            let x = n.map(dim, u);
            prop_assert!((0.0..1.0).contains(&x));
            prop_assert!((x - centre[dim]).abs() <= half_width + 1e-12);
        }

        #[test]
        fn map_is_monotone_and_stays_in_the_unit_interval(
            raw in proptest::collection::vec(0.0f64..1.0, BINS),
            a in 0.0f64..1.0,
            b in 0.0f64..1.0,
        ) {
            let sum: f64 = raw.iter().sum::<f64>() + 1e-9;
            let mut d = DrawDistribution::uniform();
            for (k, w) in raw.iter().enumerate() {
                d.weights[0][k] = (w + 1e-9 / BINS as f64) / sum;
            }
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            let (x, y) = (d.map(0, lo), d.map(0, hi));
            prop_assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
            prop_assert!(x <= y + 1e-12, "{x} > {y}");
        }
    }
}
