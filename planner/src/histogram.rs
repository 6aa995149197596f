//! The 6-degree polar histogram (docs/planner.md §4): mean obstacle distance per (elevation, azimuth) cell.
//!
//! Layout is row-major `(e, z)`: `dist[e * 60 + z]`, row 0 = -87 deg elevation, column 0 = -177 deg azimuth
//! (South, then clockwise: West 15, North 30, East 45). 0 means "no obstacle / unknown".
//! Binning uses a fast arctangent and falls back to the exact formula near cell boundaries, so every point lands
//! in exactly the cell of [`polar_to_index`]`(`[`cartesian_to_polar_histogram`]`)`.

use nalgebra::Vector3;

use super::polar::{
    ALPHA_RES, CellIndex, FAST_ATAN2_MAX_ERR_DEG, GRID_CELLS, GRID_E, GRID_Z, cartesian_to_polar_histogram,
    fast_atan2_deg, polar_to_index,
};

/// Fast-path cells closer than this to a boundary (degrees) are recomputed exactly; 5x the fast error bound.
const BOUNDARY_MARGIN_DEG: f32 = 5.0 * FAST_ATAN2_MAX_ERR_DEG;

/// `floor(u)` for non-integer `u`: round-to-nearest of `u - 0.5` by the 1.5 * 2^23 trick (no saturating
/// float-to-int conversion, which costs a compare and two selects per lane). It can differ from `floor(u)` only
/// when `u` is an exact integer (a tie), and such `u` are flagged unreliable by the caller (fraction 0 or 1). Valid for |u| < 2^22; NaN gives garbage that the
/// caller also flags (its fraction is NaN).
#[inline(always)]
fn floor_guess(u: f32) -> i32 {
    const MAGIC: f32 = 12_582_912.0;
    (((u - 0.5) + MAGIC).to_bits() as i32).wrapping_sub(MAGIC.to_bits() as i32)
}

/// Fast cell guess for the offset `d = point - origin`: `(row, column, range, reliable)`. When `reliable` is
/// false the point is within a margin of a cell boundary (or a pole/wrap) and the exact formula must decide.
/// Branch-free so that loops over points vectorise.
#[inline(always)]
fn fast_cell(dx: f32, dy: f32, dz: f32, res: f32) -> (u32, u32, f32, bool) {
    let h2 = dx * dx + dy * dy;
    let den = h2.sqrt();
    let r = (h2 + dz * dz).sqrt();
    let ue = fast_atan2_deg(dz, den) / res + 90.0 / res;
    let uz = fast_atan2_deg(dx, dy) / res + 180.0 / res;
    let ie = floor_guess(ue);
    let iz = floor_guess(uz);
    let fe = ue - ie as f32;
    let fz = uz - iz as f32;
    let m = BOUNDARY_MARGIN_DEG / res;
    let reliable = (fe > m) & (fe < 1.0 - m) & (fz > m) & (fz < 1.0 - m);
    (ie as u32, iz as u32, r, reliable)
}

/// The exact cell: `polar_to_index(cartesian_to_polar_histogram(..))`.
fn exact_cell(dx: f32, dy: f32, dz: f32, res_deg: i32) -> CellIndex {
    polar_to_index(
        cartesian_to_polar_histogram(&Vector3::new(dx, dy, dz), &Vector3::zeros()),
        res_deg,
    )
}

/// Cell (on a `res_deg` grid) and range of the ENU offset `d = point - origin`, identical to the exact
/// `polar_to_index(cartesian_to_polar_histogram(..))` but mostly without the exact `atan2`.
#[inline]
pub fn cell_and_range(dx: f32, dy: f32, dz: f32, res_deg: i32) -> (CellIndex, f32) {
    let (e, z, r, reliable) = fast_cell(dx, dy, dz, res_deg as f32);
    if reliable {
        (
            CellIndex {
                e: e as usize,
                z: z as usize,
            },
            r,
        )
    } else {
        (exact_cell(dx, dy, dz, res_deg), r)
    }
}

/// Azimuth column (on a `res_deg` grid) of a horizontal ENU offset (`dz = 0`): equal to
/// `cell_and_range(dx, dy, 0.0, res_deg).0.z`, which always takes the exact path because an elevation of exactly
/// 0 lies on a cell edge; here only the azimuth decides whether the exact `atan2` is needed.
#[inline]
pub fn azimuth_cell(dx: f32, dy: f32, res_deg: i32) -> usize {
    let res = res_deg as f32;
    let uz = fast_atan2_deg(dx, dy) / res + 180.0 / res;
    let iz = floor_guess(uz);
    let fz = uz - iz as f32;
    let m = BOUNDARY_MARGIN_DEG / res;
    if (fz > m) & (fz < 1.0 - m) {
        iz as usize
    } else {
        exact_cell(dx, dy, 0.0, res_deg).z
    }
}

/// Mean obstacle distance (metres) per 6-degree cell; 0 = empty.
#[derive(Clone, PartialEq)]
pub struct Histogram {
    dist: Box<[f32; GRID_CELLS]>,
}

impl std::fmt::Debug for Histogram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let filled = self.dist.iter().filter(|d| **d > 0.0).count();
        write!(f, "Histogram {{ {filled} filled cells }}")
    }
}

impl Default for Histogram {
    fn default() -> Self {
        Self::new()
    }
}

/// Reusable buffers for [`Histogram::build_from_soa`], so the per-tree-node rebuild does not allocate.
/// Invariant between builds: both arrays are all zero (the final pass of a build re-zeroes what it reads), so
/// no build has to clear 14 kB up front.
#[derive(Debug, Clone)]
pub struct HistogramScratch {
    count: Box<[u32; GRID_CELLS]>,
    sum: Box<[f32; GRID_CELLS]>,
}

impl Default for HistogramScratch {
    fn default() -> Self {
        Self {
            count: Box::new([0; GRID_CELLS]),
            sum: Box::new([0.0; GRID_CELLS]),
        }
    }
}

impl Histogram {
    /// An empty histogram.
    pub fn new() -> Self {
        Self {
            dist: Box::new([0.0; GRID_CELLS]),
        }
    }

    /// Builds the histogram of `points` (ENU, metres) seen from `origin` (`generateNewHistogram`).
    pub fn from_points(points: &[Vector3<f32>], origin: &Vector3<f32>) -> Self {
        let xs: Vec<f32> = points.iter().map(|p| p.x).collect();
        let ys: Vec<f32> = points.iter().map(|p| p.y).collect();
        let zs: Vec<f32> = points.iter().map(|p| p.z).collect();
        let mut h = Self::new();
        h.build_from_soa(&xs, &ys, &zs, origin, &mut HistogramScratch::default());
        h
    }

    /// Rebuilds in place from a cloud stored as separate x, y, z slices (ENU, metres; equal lengths).
    /// Each cell gets the mean range of its points, in input order; no range filter, no count threshold.
    pub fn build_from_soa(
        &mut self,
        xs: &[f32],
        ys: &[f32],
        zs: &[f32],
        origin: &Vector3<f32>,
        scratch: &mut HistogramScratch,
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2 (checked just above); the body is the same code, compiled for AVX2.
            unsafe { self.build_avx2(xs, ys, zs, origin, scratch) };
            return;
        }
        self.build_body(xs, ys, zs, origin, scratch);
    }

    /// [`Self::build_body`] compiled with AVX2 enabled (no fused multiply-add contraction: same results).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn build_avx2(
        &mut self,
        xs: &[f32],
        ys: &[f32],
        zs: &[f32],
        origin: &Vector3<f32>,
        scratch: &mut HistogramScratch,
    ) {
        self.build_body(xs, ys, zs, origin, scratch);
    }

    #[inline(always)]
    fn build_body(
        &mut self,
        xs: &[f32],
        ys: &[f32],
        zs: &[f32],
        origin: &Vector3<f32>,
        scratch: &mut HistogramScratch,
    ) {
        const CHUNK: usize = 64;
        let mut cell = [0u32; CHUNK];
        let mut range = [0f32; CHUNK];
        let mut reliable = [false; CHUNK];
        let res = ALPHA_RES as f32;
        let (ox, oy, oz) = (origin.x, origin.y, origin.z);
        for ((cx, cy), cz) in xs.chunks(CHUNK).zip(ys.chunks(CHUNK)).zip(zs.chunks(CHUNK)) {
            // Vectorisable pass (iterators, no bounds checks): fast cell guesses for the chunk.
            let out = cell.iter_mut().zip(range.iter_mut()).zip(reliable.iter_mut());
            for (((x, y), z), ((c, r), ok)) in cx.iter().zip(cy).zip(cz).zip(out) {
                let (e, zc, rr, good) = fast_cell(x - ox, y - oy, z - oz, res);
                *c = e.wrapping_mul(GRID_Z as u32).wrapping_add(zc);
                *r = rr;
                *ok = good;
            }
            // Scalar pass in input order (the sums must add up in the original's order).
            for (k, ((x, y), z)) in cx.iter().zip(cy).zip(cz).enumerate() {
                let i = if reliable[k] {
                    cell[k] as usize
                } else {
                    let c = exact_cell(x - ox, y - oy, z - oz, ALPHA_RES);
                    c.e * GRID_Z + c.z
                };
                scratch.count[i] += 1;
                scratch.sum[i] += range[k];
            }
        }
        let cells = self
            .dist
            .iter_mut()
            .zip(scratch.count.iter_mut())
            .zip(scratch.sum.iter_mut());
        for ((d, n), sum) in cells {
            *d = if *n > 0 { *sum / *n as f32 } else { 0.0 };
            *n = 0;
            *sum = 0.0;
        }
    }

    /// Distance of cell (`e`, `z`); indices wrap modulo the grid size (reads wrap, as in the original).
    pub fn get(&self, e: i32, z: i32) -> f32 {
        let e = e.rem_euclid(GRID_E as i32) as usize;
        let z = z.rem_euclid(GRID_Z as i32) as usize;
        self.dist[e * GRID_Z + z]
    }

    /// Distance of a cell.
    pub fn at(&self, c: CellIndex) -> f32 {
        self.dist[c.e * GRID_Z + c.z]
    }

    /// Sets the distance of a cell (metres; 0 = empty).
    pub fn set(&mut self, c: CellIndex, dist_m: f32) {
        self.dist[c.e * GRID_Z + c.z] = dist_m;
    }

    /// All cells, row-major (e, z).
    pub fn cells(&self) -> &[f32; GRID_CELLS] {
        &self.dist
    }

    /// True if no cell holds a value above `f32::MIN_POSITIVE` (FLT_MIN).
    pub fn is_empty(&self) -> bool {
        !self.dist.iter().any(|&d| d > f32::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polar::{PolarDeg, index_to_polar, polar_histogram_to_cartesian};
    use proptest::prelude::*;

    #[test]
    fn empty_cloud_gives_empty_histogram() {
        let h = Histogram::from_points(&[], &Vector3::new(1.0, 2.0, 3.0));
        assert!(h.is_empty());
        assert!(h.cells().iter().all(|&d| d == 0.0));
    }

    #[test]
    fn points_at_cell_centres_fill_exactly_those_cells() {
        // AV generateNewHistogramSpecificCells: points at distance 1 in chosen cells.
        let origin = Vector3::new(0.5, -1.0, 4.0);
        let cells = [(0, 0), (3, 17), (15, 30), (29, 59), (20, 45)];
        let pts: Vec<_> = cells
            .iter()
            .map(|&(e, z)| polar_histogram_to_cartesian(&index_to_polar(e, z, ALPHA_RES, 1.0), &origin))
            .collect();
        let h = Histogram::from_points(&pts, &origin);
        for e in 0..GRID_E {
            for z in 0..GRID_Z {
                let d = h.at(CellIndex { e, z });
                if cells.contains(&(e, z)) {
                    assert!((d - 1.0).abs() < 1e-4, "cell {e},{z}: {d}");
                } else {
                    assert_eq!(d, 0.0);
                }
            }
        }
        assert!(!h.is_empty());
    }

    #[test]
    fn cell_holds_mean_range() {
        let o = Vector3::zeros();
        let dir = |r: f32| polar_histogram_to_cartesian(&PolarDeg::new(3.0, 93.0, r), &o);
        let h = Histogram::from_points(&[dir(2.0), dir(4.0), dir(9.0)], &o);
        let c = polar_to_index(PolarDeg::new(3.0, 93.0, 1.0), ALPHA_RES);
        assert_eq!(c, CellIndex { e: 15, z: 45 });
        assert!((h.at(c) - 5.0).abs() < 1e-5);
    }

    #[test]
    fn reads_wrap_indices() {
        let mut h = Histogram::new();
        h.set(CellIndex { e: 29, z: 59 }, 7.0);
        assert_eq!(h.get(-1, -1), 7.0);
        assert_eq!(h.get(59, 119), 7.0);
    }

    #[test]
    fn boundary_points_follow_the_exact_formula() {
        // Points exactly on cell boundaries and on the axes take the exact path.
        for (dx, dy, dz) in [
            (0.0, -1.0, 0.0),
            (-0.0, -1.0, 0.0),
            (1.0, 0.0, 0.0),
            (0.0, 0.0, 1.0),
            (1.0, 1.0, 0.0),
        ] {
            let exact = polar_to_index(
                cartesian_to_polar_histogram(&Vector3::new(dx, dy, dz), &Vector3::zeros()),
                ALPHA_RES,
            );
            assert_eq!(cell_and_range(dx, dy, dz, ALPHA_RES).0, exact, "{dx},{dy},{dz}");
        }
    }

    #[test]
    fn azimuth_cell_equals_the_exact_cell_of_a_horizontal_offset() {
        for k in 0..200_000u32 {
            let a = (k as f32 * 0.001_8).to_radians() - std::f32::consts::PI;
            let r = 0.01 + (k % 97) as f32;
            let (dx, dy) = (r * a.sin(), r * a.cos());
            for res in [2, 6] {
                assert_eq!(
                    azimuth_cell(dx, dy, res),
                    exact_cell(dx, dy, 0.0, res).z,
                    "{dx} {dy} {res}"
                );
            }
        }
    }

    #[test]
    fn fast_cell_equals_exact_cell_on_a_dense_sweep() {
        // Deterministic LCG sweep, many more samples than the proptest, including tiny and large offsets.
        let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((s >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        for i in 0..200_000 {
            let scale = [0.01f32, 1.0, 30.0][i % 3];
            let (dx, dy, dz) = (next() * scale, next() * scale, next() * scale);
            for res in [2, 6] {
                let exact = polar_to_index(
                    cartesian_to_polar_histogram(&Vector3::new(dx, dy, dz), &Vector3::zeros()),
                    res,
                );
                assert_eq!(cell_and_range(dx, dy, dz, res).0, exact, "{dx},{dy},{dz} res {res}");
            }
        }
    }

    #[test]
    fn portable_body_equals_the_dispatched_build() {
        let origin = Vector3::new(0.2, 0.1, 3.0);
        let (mut xs, mut ys, mut zs) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..3000 {
            let a = i as f32 * 0.013;
            xs.push((a * 7.0).sin() * (1.0 + a));
            ys.push((a * 5.0).cos() * 6.0);
            zs.push((a * 3.0).sin() * 4.0);
        }
        let (mut a, mut b) = (Histogram::new(), Histogram::new());
        a.build_from_soa(&xs, &ys, &zs, &origin, &mut HistogramScratch::default());
        b.build_body(&xs, &ys, &zs, &origin, &mut HistogramScratch::default());
        let bits = |h: &Histogram| h.cells().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a), bits(&b));
    }

    proptest! {
        #[test]
        fn fast_cell_equals_exact_cell(
            x in -20.0f32..20.0, y in -20.0f32..20.0, z in -20.0f32..20.0, res in prop::sample::select(vec![2, 6, 12])
        ) {
            let p = Vector3::new(x, y, z);
            let o = Vector3::new(0.3, -0.7, 1.1);
            let exact = polar_to_index(cartesian_to_polar_histogram(&p, &o), res);
            let (fast, r) = cell_and_range(x - o.x, y - o.y, z - o.z, res);
            prop_assert_eq!(fast, exact);
            prop_assert_eq!(r, cartesian_to_polar_histogram(&p, &o).r_m);
        }
    }
}
