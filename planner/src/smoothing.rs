//! Un-normalised conic smoothing of a polar cost matrix with pole mirroring (docs/planner.md §5.4, AV
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
    x: Vec<f64>,
    y: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
}

/// Same result as [`smooth_reference`] up to f32 rounding, in O(log R) vectorised work per cell instead of O(R).
///
/// The triangle kernel is the convolution of two boxes of width R + 1, so each pass is two box sums. They are
/// accumulated in f64, which for the cost magnitudes here (1e-3 .. 1e6) is exact, so each pass yields the
/// correctly rounded kernel sum whatever the summation order (the original's f32 order is Eigen's and not
/// reproducible anyway); `reference::smooth` computes the same bits by direct kernel sums. Box sums are built by
/// doubling (widths 1, 2, 4, ... combined by the binary digits of R + 1), flat loops that vectorise.
/// Only the band of rows that can receive a non-zero value is computed; the rest is exactly 0.
/// Requires `radius <= rows` and `radius <= cols` (as [`pad_polar_matrix`]).
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

/// Original row and azimuth shift (0 or `cols / 2`) that padded row `p` copies (pole mirroring).
#[inline(always)]
fn padded_source(p: usize, rows: usize, n: usize, cols: usize) -> (usize, usize) {
    if p < n {
        (n - 1 - p, cols / 2)
    } else if p >= n + rows {
        (rows - 1 - (p - n - rows), cols / 2)
    } else {
        (p - n, 0)
    }
}

#[inline(always)]
fn smooth_body(m: &mut [f32], rows: usize, cols: usize, radius: usize, s: &mut SmoothScratch) {
    let n = radius;
    assert!(n <= rows && n <= cols, "smoothing radius {n} exceeds the matrix");
    let pr = rows + 2 * n;
    let half = cols / 2;
    let row_nonzero = |r: usize| m[r * cols..(r + 1) * cols].iter().fold(false, |a, &v| a | (v != 0.0));
    let nonzero = |p: usize| row_nonzero(padded_source(p, rows, n, cols).0);
    let (Some(lo), Some(hi)) = ((0..pr).find(|&p| nonzero(p)), (0..pr).rev().find(|&p| nonzero(p))) else {
        m.iter_mut().for_each(|v| *v = 0.0);
        return;
    };
    // Output row r reads padded rows r..=r+2n.
    let r_lo = lo.saturating_sub(2 * n);
    let r_hi = hi.min(rows - 1);
    let wr = r_hi + 1 - r_lo;
    let nin = wr + 2 * n;
    let inv = 1.0 / (n + 1) as f64;

    // Scratch buffers only ever grow (no zero-filling per call); lengths are tracked explicitly.
    let pc = cols + 2 * n;
    let cap = pr * pc;
    for v in [&mut s.x, &mut s.y, &mut s.a, &mut s.b] {
        if v.len() < cap {
            v.resize(cap, 0.0);
        }
    }

    // Pass 1, along elevation: padded rows r_lo .. r_lo+nin (azimuth unpadded) as f64, box of box over rows.
    for (i, dst) in s.x[..nin * cols].chunks_exact_mut(cols).enumerate() {
        let (src, shift) = padded_source(r_lo + i, rows, n, cols);
        let row = &m[src * cols..(src + 1) * cols];
        // A shift of cols/2 turns the row by 180 degrees: columns [half, 2 half) first, then [0, half).
        if shift == 0 {
            dst.iter_mut().zip(row).for_each(|(d, &v)| *d = v as f64);
        } else {
            let (d1, rest) = dst.split_at_mut(half);
            let (d2, d3) = rest.split_at_mut(half);
            d1.iter_mut()
                .zip(&row[half..2 * half])
                .for_each(|(d, &v)| *d = v as f64);
            d2.iter_mut().zip(&row[..half]).for_each(|(d, &v)| *d = v as f64);
            d3.iter_mut().zip(&row[2 * half..]).for_each(|(d, &v)| *d = v as f64);
        }
    }
    let len = box_sum(&mut s.x, nin * cols, cols, n + 1, &mut s.y, &mut s.a, &mut s.b);
    let len = box_sum(&mut s.y, len, cols, n + 1, &mut s.x, &mut s.a, &mut s.b);
    debug_assert_eq!(len, wr * cols);
    // Pass-1 output rounded to f32 like the original's float matrix, stored with the azimuth wrap padding.
    for (t, out) in s.x[..len].chunks_exact(cols).zip(s.y[..wr * pc].chunks_exact_mut(pc)) {
        let round = |v: f64| (v * inv) as f32 as f64;
        let (left, rest) = out.split_at_mut(n);
        let (mid, right) = rest.split_at_mut(cols);
        mid.iter_mut().zip(t).for_each(|(o, &v)| *o = round(v));
        left.copy_from_slice(&mid[cols - n..]);
        right.copy_from_slice(&mid[..n]);
    }

    // Pass 2, along azimuth: box of box with stride 1 over the flat rows; sums that would straddle two rows
    // are computed but never read.
    let len = box_sum(&mut s.y, wr * pc, 1, n + 1, &mut s.x, &mut s.a, &mut s.b);
    box_sum(&mut s.x, len, 1, n + 1, &mut s.y, &mut s.a, &mut s.b);
    m[..r_lo * cols].iter_mut().for_each(|v| *v = 0.0);
    m[(r_hi + 1) * cols..].iter_mut().for_each(|v| *v = 0.0);
    for (r, out) in m[r_lo * cols..(r_hi + 1) * cols].chunks_exact_mut(cols).enumerate() {
        let t = &s.y[r * pc..r * pc + cols];
        out.iter_mut().zip(t).for_each(|(o, &v)| *o = (v * inv) as f32);
    }
}

/// Sizes a scratch buffer without clearing it: callers overwrite every element they read.
fn reuse<T: Copy + Default>(v: &mut Vec<T>, len: usize) {
    if v.len() != len {
        v.resize(len, T::default());
    }
}

/// `dst[k] = sum of src[k + j * stride] for j in 0..w` for every `k` that stays inside `src[..len]`; returns
/// the number of sums, `len - (w - 1) * stride`. All four buffers have the same (sufficient) length.
///
/// Built by doubling: sums of width 1, 2, 4, ... (ping-pong in `a` and `b`); those whose bit is set in `w` are
/// added into `dst` at the running offset. All sums are exact in f64 for the planner's magnitudes, so the order
/// is immaterial. For a power of two (the default R + 1 = 8) the last doubling simply becomes `dst`.
#[inline(always)]
fn box_sum(
    src: &mut Vec<f64>,
    len: usize,
    stride: usize,
    w: usize,
    dst: &mut Vec<f64>,
    a: &mut Vec<f64>,
    b: &mut Vec<f64>,
) -> usize {
    debug_assert!(w >= 1);
    let out_len = len.saturating_sub((w - 1) * stride);
    let (mut bits, mut width, mut offset, mut first) = (w, 1usize, 0usize, true);
    // Which buffer holds the current width: 0 = src, 1 = a, 2 = b.
    let mut which = 0u8;
    loop {
        if bits & 1 == 1 {
            if first && bits == 1 {
                // The only set bit: the current sums are the result (offset is 0).
                std::mem::swap(
                    dst,
                    match which {
                        0 => src,
                        1 => a,
                        _ => b,
                    },
                );
                return out_len;
            }
            let cur: &[f64] = match which {
                0 => src,
                1 => a,
                _ => b,
            };
            let part = &cur[offset * stride..offset * stride + out_len];
            if first {
                dst[..out_len].copy_from_slice(part);
                first = false;
            } else {
                dst[..out_len].iter_mut().zip(part).for_each(|(d, &p)| *d += p);
            }
            offset += width;
        }
        bits >>= 1;
        if bits == 0 {
            return out_len;
        }
        let d = width * stride;
        let valid = len.saturating_sub((2 * width - 1) * stride);
        which = match which {
            0 => {
                double_into(src, d, valid, a);
                1
            }
            1 => {
                double_into(a, d, valid, b);
                2
            }
            _ => {
                double_into(b, d, valid, a);
                1
            }
        };
        width *= 2;
    }
}

/// `out[k] = cur[k] + cur[k + d]` for `k < valid`.
#[inline(always)]
fn double_into(cur: &[f64], d: usize, valid: usize, out: &mut [f64]) {
    for ((o, x), y) in out[..valid].iter_mut().zip(&cur[..valid]).zip(&cur[d..d + valid]) {
        *o = x + y;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polar::{GRID_E, GRID_Z};

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
    fn portable_body_equals_the_dispatched_path() {
        // The AVX2 build and the baseline build of the same body must agree bit for bit.
        let mut s: u64 = 11;
        let mut next = || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (s >> 40) as f32 / (1u64 << 24) as f32
        };
        for radius in [0, 1, 4, 7, 9] {
            let m: Vec<f32> = (0..GRID_E * GRID_Z)
                .map(|_| if next() < 0.3 { next() * 10_000.0 } else { 0.0 })
                .collect();
            let (mut a, mut b) = (m.clone(), m);
            smooth_fast(&mut a, GRID_E, GRID_Z, radius, &mut SmoothScratch::default());
            smooth_body(&mut b, GRID_E, GRID_Z, radius, &mut SmoothScratch::default());
            assert_eq!(
                a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                b.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
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
