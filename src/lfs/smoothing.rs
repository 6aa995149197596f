//! Un-normalised conic smoothing of a polar cost matrix with pole mirroring (3dvfh.md §5.4, AV
//! `smoothPolarMatrix` / `padPolarMatrix` / `getConicKernel`).
//!
//! Matrices are row-major `rows x cols` (rows = elevation, cols = azimuth). The kernel weight of offset `k` is
//! `(R + 1 - |k|) / (R + 1)`, so each pass has gain `R + 1` (64 in 2-D for R = 7): deliberate in the original.
//! Padding beyond a pole takes the mirrored rows **shifted by 180 degrees** (half the columns); azimuth padding
//! wraps around.

/// Pads `m` (`rows x cols`) by `n` cells on every side following the polar wrapping rules.
/// Returns a `(rows + 2n) x (cols + 2n)` row-major matrix.
pub fn pad_polar_matrix(m: &[f32], rows: usize, cols: usize, n: usize) -> Vec<f32> {
    let mut p = Vec::new();
    pad_polar_matrix_into(m, rows, cols, n, &mut p);
    p
}

/// [`pad_polar_matrix`] into a reused buffer.
pub fn pad_polar_matrix_into(m: &[f32], rows: usize, cols: usize, n: usize, p: &mut Vec<f32>) {
    let (pr, pc) = (rows + 2 * n, cols + 2 * n);
    // Every cell is written below when n <= rows; only zero-fill otherwise (or on a size change).
    if n > rows {
        p.clear();
    }
    reuse(p, pr * pc);
    let half = cols / 2;
    for r in 0..rows {
        p[(r + n) * pc + n..(r + n) * pc + n + cols].copy_from_slice(&m[r * cols..(r + 1) * cols]);
    }
    for k in 0..n.min(rows) {
        // Beyond the lower pole: padded row k mirrors original row n-1-k, turned by 180 degrees.
        let src = (n - 1 - k) * cols;
        let dst = k * pc + n;
        p[dst..dst + half].copy_from_slice(&m[src + half..src + 2 * half]);
        p[dst + half..dst + 2 * half].copy_from_slice(&m[src..src + half]);
        // Beyond the upper pole: padded row rows+n+k mirrors original row rows-1-k.
        let src = (rows - 1 - k) * cols;
        let dst = (rows + n + k) * pc + n;
        p[dst..dst + half].copy_from_slice(&m[src + half..src + 2 * half]);
        p[dst + half..dst + 2 * half].copy_from_slice(&m[src..src + half]);
    }
    for r in 0..pr {
        let row = &mut p[r * pc..(r + 1) * pc];
        for c in 0..n {
            row[c] = row[cols + c];
            row[n + cols + c] = row[n + c];
        }
    }
}

/// The conic kernel `max(0, 1 + R - |k - R|)` scaled by `1 / max` (multiplication by the reciprocal, in f32).
pub fn conic_kernel(radius: usize) -> Vec<f32> {
    let r = radius as i32;
    let mut k: Vec<f32> = (0..2 * r + 1).map(|i| (1 + r - (i - r).abs()).max(0) as f32).collect();
    let scale = 1.0 / (r + 1) as f32;
    k.iter_mut().for_each(|v| *v *= scale);
    k
}

/// Reference smoothing, a direct transcription of the two kernel passes (used to check [`smooth_fast`]).
pub fn smooth_reference(m: &mut [f32], rows: usize, cols: usize, radius: usize) {
    let n = radius;
    let mut p = pad_polar_matrix(m, rows, cols, n);
    let (pr, pc) = (rows + 2 * n, cols + 2 * n);
    let kernel = conic_kernel(n);
    let mut col = vec![0.0f32; pr];
    for c in 0..pc {
        for (r, v) in col.iter_mut().enumerate() {
            *v = p[r * pc + c];
        }
        for r in 0..rows {
            p[(r + n) * pc + c] = col[r..r + 2 * n + 1].iter().zip(&kernel).map(|(a, b)| a * b).sum();
        }
    }
    for r in 0..rows {
        let row = &p[(r + n) * pc..(r + n + 1) * pc];
        for c in 0..cols {
            m[r * cols + c] = row[c..c + 2 * n + 1].iter().zip(&kernel).map(|(a, b)| a * b).sum();
        }
    }
}

/// Reusable buffers for [`smooth_fast`].
#[derive(Debug, Clone, Default)]
pub struct SmoothScratch {
    padded: Vec<f32>,
    box_sums: Vec<f64>,
    acc: Vec<f64>,
    pass1_t: Vec<f32>,
    col_box: Vec<f64>,
}

/// Same result as [`smooth_reference`] up to f32 rounding, in O(1) work per cell instead of O(R).
///
/// The triangle kernel is the convolution of two boxes of width R + 1, so each pass is two running box sums.
/// They are accumulated in f64, which for the cost magnitudes here (1e-3 .. 1e6) is exact, so each pass yields
/// the correctly rounded kernel sum (the original's f32 sum order is Eigen's and not reproducible anyway).
/// Only the band of rows that can receive a non-zero value is computed; the rest is exactly 0.
pub fn smooth_fast(m: &mut [f32], rows: usize, cols: usize, radius: usize, s: &mut SmoothScratch) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above); the body is the same code, compiled for AVX2.
        unsafe { smooth_avx2(m, rows, cols, radius, s) };
        return;
    }
    smooth_body(m, rows, cols, radius, s);
}

/// [`smooth_body`] compiled with AVX2 enabled (no fused multiply-add contraction: same results).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn smooth_avx2(m: &mut [f32], rows: usize, cols: usize, radius: usize, s: &mut SmoothScratch) {
    smooth_body(m, rows, cols, radius, s);
}

#[inline(always)]
fn smooth_body(m: &mut [f32], rows: usize, cols: usize, radius: usize, s: &mut SmoothScratch) {
    let n = radius;
    pad_polar_matrix_into(m, rows, cols, n, &mut s.padded);
    let p = &s.padded;
    let (pr, pc) = (rows + 2 * n, cols + 2 * n);
    let nonzero = |r: usize| p[r * pc..(r + 1) * pc].iter().any(|&v| v != 0.0);
    let (Some(lo), Some(hi)) = ((0..pr).find(|&r| nonzero(r)), (0..pr).rev().find(|&r| nonzero(r))) else {
        m.iter_mut().for_each(|v| *v = 0.0);
        return;
    };
    // Output row r reads padded rows r..=r+2n.
    let r_lo = lo.saturating_sub(2 * n);
    let r_hi = hi.min(rows - 1);
    let wr = r_hi + 1 - r_lo;
    let inv = 1.0 / (n + 1) as f64;

    // Pass 1, along elevation, all padded columns at once. B[j] = sum of padded rows j..=j+n, j from r_lo.
    let nb = wr + n;
    reuse(&mut s.box_sums, nb * pc);
    s.acc.clear();
    s.acc.resize(pc, 0.0);
    for r in r_lo..=r_lo + n {
        add_row(&mut s.acc, &p[r * pc..(r + 1) * pc], 1.0);
    }
    s.box_sums[..pc].copy_from_slice(&s.acc);
    for j in 1..nb {
        let g = r_lo + j;
        running_step(&mut s.acc, &p[(g + n) * pc..(g + n + 1) * pc], &p[(g - 1) * pc..g * pc]);
        s.box_sums[j * pc..(j + 1) * pc].copy_from_slice(&s.acc);
    }
    // T[r] = sum of B[r..=r+n]; pass-1 output stored transposed (pc x wr) for a vectorisable pass 2.
    reuse(&mut s.pass1_t, pc * wr);
    s.acc.iter_mut().for_each(|v| *v = 0.0);
    for a in 0..=n {
        let b = &s.box_sums[a * pc..(a + 1) * pc];
        s.acc.iter_mut().zip(b).for_each(|(x, y)| *x += y);
    }
    for r in 0..wr {
        if r > 0 {
            let add = &s.box_sums[(r + n) * pc..(r + n + 1) * pc];
            let sub = &s.box_sums[(r - 1) * pc..r * pc];
            s.acc.iter_mut().zip(add).zip(sub).for_each(|((a, x), y)| *a += x - y);
        }
        for (c, a) in s.acc.iter().enumerate() {
            s.pass1_t[c * wr + r] = (a * inv) as f32;
        }
    }

    // Pass 2, along azimuth, all band rows at once on the transposed pass-1 output.
    let q = &s.pass1_t;
    reuse(&mut s.col_box, (cols + n) * wr);
    s.acc.clear();
    s.acc.resize(wr, 0.0);
    for c in 0..=n {
        add_row(&mut s.acc, &q[c * wr..(c + 1) * wr], 1.0);
    }
    s.col_box[..wr].copy_from_slice(&s.acc);
    for j in 1..cols + n {
        running_step(&mut s.acc, &q[(j + n) * wr..(j + n + 1) * wr], &q[(j - 1) * wr..j * wr]);
        s.col_box[j * wr..(j + 1) * wr].copy_from_slice(&s.acc);
    }
    m.iter_mut().for_each(|v| *v = 0.0);
    s.acc.iter_mut().for_each(|v| *v = 0.0);
    for a in 0..=n {
        let b = &s.col_box[a * wr..(a + 1) * wr];
        s.acc.iter_mut().zip(b).for_each(|(x, y)| *x += y);
    }
    for c in 0..cols {
        if c > 0 {
            let add = &s.col_box[(c + n) * wr..(c + n + 1) * wr];
            let sub = &s.col_box[(c - 1) * wr..c * wr];
            s.acc.iter_mut().zip(add).zip(sub).for_each(|((a, x), y)| *a += x - y);
        }
        for (r, a) in s.acc.iter().enumerate() {
            m[(r_lo + r) * cols + c] = (a * inv) as f32;
        }
    }
}

/// Sizes a scratch buffer without clearing it: callers overwrite every element they read.
fn reuse<T: Copy + Default>(v: &mut Vec<T>, len: usize) {
    if v.len() != len {
        v.resize(len, T::default());
    }
}

/// `acc += add - sub` element-wise (one step of a running box sum).
#[inline]
fn running_step(acc: &mut [f64], add: &[f32], sub: &[f32]) {
    acc.iter_mut()
        .zip(add)
        .zip(sub)
        .for_each(|((a, &x), &y)| *a += x as f64 - y as f64);
}

#[inline]
fn add_row(acc: &mut [f64], row: &[f32], sign: f64) {
    acc.iter_mut().zip(row).for_each(|(a, &v)| *a += sign * v as f64);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lfs::polar::{GRID_E, GRID_Z};

    #[rustfmt::skip]
    const AV_SMOOTH_EXPECTED: [f32; 200] = [
         8., 0.,   4.,   8.,  12.,  16.,  20.,  16.,  12.,   8.,   4., 0.,  8., 16.,  24.,  32.,  40.,  32.,  24., 16.,
        12., 0.,   0.,   0.,   0.,   0.,   0.,   0.,   0.,   0.,   0., 0., 12., 24.,  36.,  48.,  60.,  48.,  36., 24.,
        16., 0.,  -4.,  -8., -12., -16., -20., -16., -12.,  -8.,  -4., 0., 16., 32.,  48.,  64.,  80.,  64.,  48., 32.,
        20., 0.,  -8., -16., -24., -32., -40., -32., -24., -16.,  -8., 0., 20., 40.,  60.,  80., 100.,  80.,  60., 40.,
        16., 0., -12., -24., -36., -48., -60., -48., -36., -24., -12., 0., 16., 32.,  48.,  64.,  80.,  64.,  48., 32.,
        12., 0., -16., -32., -48., -64., -80., -64., -48., -32., -16., 0., 12., 24.,  36.,  48.,  60.,  48.,  36., 24.,
         8., 0., -20., -40., -60., -80.,-100., -80., -60., -40., -20., 0.,  8., 16.,  24.,  32.,  40.,  32.,  24., 16.,
         4., 0., -16., -32., -48., -64., -80., -64., -48., -32., -16., 0.,  4.,  8.,  12.,  16.,  20.,  16.,  12.,  8.,
         0., 0., -12., -24., -36., -48., -60., -48., -36., -24., -12., 0.,  0.,  0.,   0.,   0.,   0.,   0.,   0.,  0.,
        -4., 0.,  -8., -16., -24., -32., -40., -32., -24., -16.,  -8., 0., -4., -8., -12., -16., -20., -16., -12., -8.,
    ];

    fn av_input() -> Vec<f32> {
        let mut m = vec![0.0f32; 200];
        m[3 * 20 + 16] = 100.0;
        m[6 * 20 + 6] = -100.0;
        m
    }

    #[test]
    fn known_answer_av_smooth_matrix() {
        // AV test smoothMatrix: a 10 x 20 matrix, radius 4, two single cells.
        let mut m = av_input();
        smooth_reference(&mut m, 10, 20, 4);
        for (i, (a, b)) in m.iter().zip(AV_SMOOTH_EXPECTED.iter()).enumerate() {
            assert!((a - b).abs() < 1e-4, "cell {i}: {a} vs {b}");
        }
        let mut f = av_input();
        smooth_fast(&mut f, 10, 20, 4, &mut SmoothScratch::default());
        for (i, (a, b)) in f.iter().zip(AV_SMOOTH_EXPECTED.iter()).enumerate() {
            assert!((a - b).abs() < 1e-4, "fast cell {i}: {a} vs {b}");
        }
    }

    #[test]
    fn kernel_is_unnormalised_triangle() {
        let k = conic_kernel(7);
        assert_eq!(k.len(), 15);
        assert_eq!(k[7], 1.0);
        assert_eq!(k[0], 0.125);
        assert_eq!(k.iter().sum::<f32>(), 8.0);
    }

    #[test]
    fn uniform_field_gain_is_64() {
        let mut m = vec![1.0f32; GRID_E * GRID_Z];
        smooth_fast(&mut m, GRID_E, GRID_Z, 7, &mut SmoothScratch::default());
        assert!(m.iter().all(|&v| (v - 64.0).abs() < 1e-4));
    }

    #[test]
    fn padding_wraps_azimuth_and_mirrors_poles_with_180_shift() {
        let (rows, cols, n) = (GRID_E, GRID_Z, 3);
        let m: Vec<f32> = (0..rows * cols).map(|i| i as f32).collect();
        let p = pad_polar_matrix(&m, rows, cols, n);
        let pc = cols + 2 * n;
        let at = |r: usize, c: usize| p[r * pc + c];
        let orig = |r: usize, c: usize| m[r * cols + c];
        for r in 0..rows {
            for c in 0..cols {
                assert_eq!(at(r + n, c + n), orig(r, c));
            }
            // Azimuth wrap: padded column 0 is original column cols-n, the first right pad column is column 0.
            assert_eq!(at(r + n, 0), orig(r, cols - n));
            assert_eq!(at(r + n, n + cols), orig(r, 0));
        }
        for k in 0..n {
            for c in 0..cols {
                // Beyond -90: row n-1-k turned by 180 deg (30 columns).
                assert_eq!(at(k, c + n), orig(n - 1 - k, (c + cols / 2) % cols));
                // Beyond +90: row rows-1-k turned by 180 deg.
                assert_eq!(at(rows + n + k, c + n), orig(rows - 1 - k, (c + cols / 2) % cols));
            }
        }
        // Corners wrap too.
        assert_eq!(at(0, 0), at(0, cols));
    }

    #[test]
    fn smoothing_is_symmetric_and_spreads_only_within_radius() {
        let (rows, cols, r) = (GRID_E, GRID_Z, 7);
        let mut m = vec![0.0f32; rows * cols];
        m[15 * cols + 30] = 100.0;
        let before = m.clone();
        smooth_fast(&mut m, rows, cols, r, &mut SmoothScratch::default());
        assert_eq!(m[15 * cols + 30], 100.0);
        for de in 1..=7usize {
            for dz in 0..=7usize {
                let w = (8 - de) as f32 * (8 - dz) as f32 / 64.0 * 100.0;
                for (e, z) in [
                    (15 + de, 30 + dz),
                    (15 - de, 30 - dz),
                    (15 + de, 30 - dz),
                    (15 - de, 30 + dz),
                ] {
                    assert!((m[e * cols + z] - w).abs() < 1e-3, "{e},{z}");
                }
            }
        }
        assert_eq!(m[23 * cols + 30], 0.0);
        assert_eq!(m[15 * cols + 38], 0.0);
        assert!(m.iter().zip(&before).all(|(a, b)| a >= b));
    }

    #[test]
    fn cost_near_a_pole_reaches_over_it_to_the_opposite_azimuth() {
        let (rows, cols) = (GRID_E, GRID_Z);
        let mut m = vec![0.0f32; rows * cols];
        m[cols + 5] = 80.0; // row 1 (-81 deg), column 5
        smooth_fast(&mut m, rows, cols, 7, &mut SmoothScratch::default());
        // Column 35 is 180 deg away; row 0 there is 3 cells away over the pole (mirror of row 1 is pad row n-2).
        assert!(m[35] > 0.0);
        // An equally far cell on the same side without the pole mirror is the reference for symmetry.
        let mut a = vec![0.0f32; rows * cols];
        a[cols + 5] = 80.0;
        let mut b = a.clone();
        smooth_reference(&mut b, rows, cols, 7);
        smooth_fast(&mut a, rows, cols, 7, &mut SmoothScratch::default());
        assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= 1e-5 * y.abs().max(1.0)));
    }

    #[test]
    fn fast_equals_reference_on_random_matrices() {
        let mut s: u64 = 7;
        let mut next = || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut scratch = SmoothScratch::default();
        for trial in 0..40 {
            let mut m: Vec<f32> = (0..GRID_E * GRID_Z)
                .map(|_| if next() < 0.3 { next() * 10_000.0 } else { 0.0 })
                .collect();
            if trial % 2 == 1 {
                // Sparse band of rows (sky above, nothing below): exercises the banded fast path.
                let (lo, hi) = (trial % 7 * 3, trial % 7 * 3 + 4);
                for (i, v) in m.iter_mut().enumerate() {
                    if !(lo..=hi).contains(&(i / GRID_Z)) {
                        *v = 0.0;
                    }
                }
            }
            let mut r = m.clone();
            let radius = [7, 5, 3, 1][trial % 4];
            smooth_reference(&mut r, GRID_E, GRID_Z, radius);
            smooth_fast(&mut m, GRID_E, GRID_Z, radius, &mut scratch);
            for (a, b) in m.iter().zip(&r) {
                assert!((a - b).abs() <= 2e-6 * b.abs().max(1.0), "radius {radius}: {a} vs {b}");
            }
        }
    }
}
