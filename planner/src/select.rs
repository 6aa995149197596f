//! The cheapest directions of one tree expansion (docs/planner.md §5-6) without smoothing the whole cost matrix: the
//! same candidates, with the same bits, as [`cost_matrix`] followed by [`best_candidates`].
//!
//! The smoothed distance cost is never negative, so a cell's total cost is at least its unsmoothed "other" cost.
//! Rows are therefore smoothed one by one, in ascending order of their smallest "other" cost, and the search stops
//! as soon as the next row's smallest "other" cost exceeds the worst of the `n` kept candidates: no cell of that
//! row (or of any later one) can still enter. Each smoothed row is the original's two-pass conic smoothing at that
//! row only (its f64 kernel sums are exact, as in [`super::smoothing::smooth_fast`], so the bits agree).

use super::cost::{
    Candidate, CostContext, CostInputs, CostScratch, TopN, best_candidates, cost_matrix, fill_matrices,
    obstacle_facing_goal, total_key,
};
use super::histogram::Histogram;
use super::params::CostParams;
use super::polar::{ALPHA_RES, GRID_CELLS, GRID_E, GRID_Z, index_to_polar};

// A row's cells are tracked in one u64 mask.
const _: () = assert!(GRID_Z <= 64);

/// Reusable buffers of [`best_candidates_lazy`].
#[derive(Debug, Clone)]
pub struct SelectScratch {
    other: Box<[f32; GRID_CELLS]>,
    dist: Vec<f32>,
    x: Vec<f64>,
    w: Vec<f64>,
    padded: Vec<f64>,
    pad_state: Vec<u8>,
    fallback: CostScratch,
    total: Box<[f32; GRID_CELLS]>,
}

impl Default for SelectScratch {
    fn default() -> Self {
        Self {
            other: Box::new([0.0; GRID_CELLS]),
            dist: vec![0.0; GRID_CELLS],
            x: Vec::new(),
            w: Vec::new(),
            padded: Vec::new(),
            pad_state: Vec::new(),
            fallback: CostScratch::default(),
            total: Box::new([0.0; GRID_CELLS]),
        }
    }
}

/// The `n` cheapest directions from `inputs.origin` into `out`, sorted by ascending total cost (ties: lower cell
/// index first): exactly `cost_matrix(..)` then `best_candidates(.., n, ..)`, usually at a fraction of the work.
#[allow(clippy::too_many_arguments)]
pub fn best_candidates_lazy(
    hist: &Histogram,
    inputs: &CostInputs,
    k: &CostParams,
    smoothing_radius: usize,
    min_range_m: f32,
    max_range_m: f32,
    n: usize,
    scratch: &mut SelectScratch,
    out: &mut Vec<Candidate>,
) {
    out.clear();
    if n == 0 {
        return;
    }
    let facing = obstacle_facing_goal(hist, &inputs.goal, &inputs.origin, min_range_m, max_range_m);
    let ctx = CostContext::new(inputs, facing);
    fill_matrices(hist, &ctx, k, &mut scratch.other, &mut scratch.dist);
    if smoothing_radius > GRID_E.min(GRID_Z) || !select(scratch, smoothing_radius, n.min(GRID_CELLS), out) {
        // Outside the premises of the lazy search: the whole matrix (same result, or the same panic).
        let total = &mut scratch.total;
        cost_matrix(
            hist,
            inputs,
            k,
            smoothing_radius,
            min_range_m,
            max_range_m,
            &mut scratch.fallback,
            total,
        );
        best_candidates(total, n, out);
    }
}

/// The search over rows; AVX2-compiled where available (plain f64 additions and products: same bits).
/// Returns false, with `out` untouched, outside its premises: a non-finite "other" cost, or a distance cost that
/// is not +0 or positive and finite.
fn select(s: &mut SelectScratch, radius: usize, n: usize, out: &mut Vec<Candidate>) -> bool {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked just above); the body is the same code, compiled for AVX2.
        return unsafe { select_avx2(s, radius, n, out) };
    }
    select_body(s, radius, n, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn select_avx2(s: &mut SelectScratch, radius: usize, n: usize, out: &mut Vec<Candidate>) -> bool {
    select_body(s, radius, n, out)
}

#[inline(always)]
fn select_body(s: &mut SelectScratch, radius: usize, n: usize, out: &mut Vec<Candidate>) -> bool {
    // Rows by ascending smallest "other" key (ties: lower row first), as one sortable i64 each.
    let mut order = [0i64; GRID_E];
    let mut finite = true;
    for (r, (m, o)) in order.iter_mut().zip(s.other.chunks_exact(GRID_Z)).enumerate() {
        let min = o.iter().fold(i32::MAX, |a, &c| a.min(total_key(c)));
        // Integer folds (they vectorise): finite means |bits| below those of infinity.
        let abs_max = o.iter().fold(0u32, |a, &c| a.max(c.to_bits() & 0x7fff_ffff));
        finite &= abs_max < f32::INFINITY.to_bits();
        *m = (i64::from(min) << 8) | r as i64;
    }
    let mut row_nonzero = [false; GRID_E];
    for (nz, d) in row_nonzero.iter_mut().zip(s.dist.chunks_exact(GRID_Z)) {
        // +0 or positive finite (no -0, negative, infinite or NaN distance cost): bits below those of infinity.
        // Given that, a row is non-zero exactly when some bit is set.
        let (max, any) = d
            .iter()
            .fold((0u32, 0u32), |(m, a), &v| (m.max(v.to_bits()), a | v.to_bits()));
        finite &= max < f32::INFINITY.to_bits();
        *nz = any != 0;
    }
    if !finite {
        return false;
    }
    order.sort_unstable();
    pad_rows(s, radius, &row_nonzero);
    let mut band = Band::new();
    let mut top = TopN::new(n);
    for &packed in &order {
        if (packed >> 8) as i32 > top.bound() {
            break;
        }
        let r = (packed & 0xff) as usize;
        let base = r * GRID_Z;
        let mut keys = [0i32; GRID_Z];
        for (k, &o) in keys.iter_mut().zip(&s.other[base..base + GRID_Z]) {
            *k = total_key(o);
        }
        // Cells whose "other" cost alone is worse than the worst kept cannot enter (the smoothed part is never
        // negative); the bound only falls while the row is scanned, so this mask is conservative.
        let bound = top.bound();
        let mask = keys
            .iter()
            .enumerate()
            .fold(0u64, |m, (z, &k)| m | (u64::from(k <= bound) << z));
        if mask == 0 {
            continue;
        }
        let (first, last) = (mask.trailing_zeros() as usize, 63 - mask.leading_zeros() as usize);
        let smoothed = pass1_row(s, &mut band, r, radius);
        let mut sums = [0.0f64; GRID_Z];
        if smoothed {
            kernel_sums(&s.x, &s.w, radius, first, last, &mut sums);
        }
        // Every cell of first..=last now has its exact total; any of them may be offered.
        let inv = 1.0 / (radius + 1) as f64;
        let total = &mut s.total[base + first..base + last + 1];
        let other = &s.other[base + first..base + last + 1];
        for ((t, &o), &v) in total.iter_mut().zip(other).zip(&sums[first..last + 1]) {
            *t = o + (v * inv) as f32;
        }
        top.offer_cells(total, base + first);
    }
    out.extend(top.kept().iter().map(|&(_, i)| {
        let i = i as usize;
        let p = index_to_polar(i / GRID_Z, i % GRID_Z, ALPHA_RES, 1.0);
        Candidate {
            cost: s.total[i],
            e_deg: p.e_deg,
            z_deg: p.z_deg,
        }
    }));
    true
}

/// `sums[z]` = the conic kernel sum `sum_k w_k x[z + k]` of the padded pass-1 row `x` for `z` in
/// `first..=last`: directly at `first`, then stepped along the row as `out(z+1) = out(z) + D(z)` with
/// `D(z) = U(z) - L(z)`, the box sums `U(z) = x[z+R+1 ..= z+2R+1]` and `L(z) = x[z ..= z+R]`, and
/// `D(z+1) = D(z) + (x[z+2R+2] - x[z+R+1]) - (x[z+R+1] - x[z])`. All exact f64 sums (as everywhere in the
/// smoothing), so stepping gives the same bits as summing each kernel afresh.
#[inline(always)]
fn kernel_sums(x: &[f64], w: &[f64], radius: usize, first: usize, last: usize, sums: &mut [f64; GRID_Z]) {
    let n2 = 2 * radius;
    let mut sum = x[first..=first + n2].iter().zip(w).fold(0.0, |a, (&v, &w)| a + w * v);
    sums[first] = sum;
    if first == last {
        return;
    }
    let l: f64 = x[first..=first + radius].iter().sum();
    let u: f64 = x[first + radius + 1..=first + n2 + 1].iter().sum();
    let mut d = u - l;
    // Second differences for z in first..last (x has one spare element past the padding for the last one, whose
    // value is never used).
    let mut e = [0.0f64; GRID_Z];
    let len = last - first;
    let (a, b, c) = (&x[first + n2 + 2..], &x[first + radius + 1..], &x[first..]);
    for (k, ek) in e[..len].iter_mut().enumerate() {
        *ek = (a[k] - b[k]) - (b[k] - c[k]);
    }
    for (s, &ek) in sums[first + 1..=last].iter_mut().zip(&e[..len]) {
        sum += d;
        *s = sum;
        d += ek;
    }
}

/// Original row and azimuth shift (0 or half a turn) of virtual row `v` (`-rows <= v < 2 rows`): beyond a pole
/// the mirrored row turned by 180 degrees, as `pad_polar_matrix`.
#[inline(always)]
fn source_row(v: isize) -> (usize, usize) {
    let rows = GRID_E as isize;
    if v < 0 {
        ((-1 - v) as usize, GRID_Z / 2)
    } else if v >= rows {
        ((2 * rows - 1 - v) as usize, GRID_Z / 2)
    } else {
        (v as usize, 0)
    }
}

/// Padded row `p` (`0 .. rows + 2R`) of pass 1 is virtual row `p - R` of the distance matrix (mirrored and
/// turned by half a turn beyond a pole). Marks which padded rows hold a non-zero cell (`s.pad_state`: 0 = all
/// zero, 1 = not yet converted) and sets the kernel weights `s.w`; rows are converted to f64 on first use.
#[inline(always)]
fn pad_rows(s: &mut SelectScratch, n: usize, row_nonzero: &[bool; GRID_E]) {
    let pr = GRID_E + 2 * n;
    if s.padded.len() < pr * GRID_Z {
        s.padded.resize(pr * GRID_Z, 0.0);
    }
    s.pad_state.clear();
    s.pad_state
        .extend((0..pr).map(|p| u8::from(row_nonzero[source_row(p as isize - n as isize).0])));
    // One more, all zero, past the end: the box sum U of the last row reaches it.
    s.pad_state.push(0);
    if s.w.len() != 2 * n + 1 {
        s.w = (0..=2 * n)
            .map(|k| (n + 1) as f64 - (k as f64 - n as f64).abs())
            .collect();
    }
}

/// Padded row `p` as f64 (state 2 once converted).
#[inline(always)]
fn convert_row(s: &mut SelectScratch, p: usize, n: usize) {
    let (src, shift) = source_row(p as isize - n as isize);
    let row = &s.dist[src * GRID_Z..(src + 1) * GRID_Z];
    let dst = &mut s.padded[p * GRID_Z..(p + 1) * GRID_Z];
    // Column c takes row[(c + shift) % cols].
    let (lo, hi) = dst.split_at_mut(GRID_Z - shift);
    lo.iter_mut().zip(&row[shift..]).for_each(|(a, &d)| *a = d as f64);
    hi.iter_mut().zip(&row[..shift]).for_each(|(a, &d)| *a = d as f64);
    s.pad_state[p] = 2;
}

type Row = [f64; GRID_Z];

/// Pass-1 kernel sums at one row `r` (padded rows `r ..= r + 2R`): `t = sum_k w_k X[r + k]` and the box sums
/// `l = X[r ..= r + R]`, `u = X[r + R + 1 ..= r + 2R + 1]` that step it to a neighbouring row.
#[derive(Clone, Copy)]
struct RowSums {
    r: usize,
    t: Row,
    l: Row,
    u: Row,
}

/// The pass-1 sums at both ends of the band of rows computed so far, so that the next row (the search goes
/// outwards from the cheapest row) costs a few row additions instead of a whole kernel.
struct Band {
    lo: RowSums,
    hi: RowSums,
    valid: bool,
}

impl Band {
    fn new() -> Self {
        let z = RowSums {
            r: 0,
            t: [0.0; GRID_Z],
            l: [0.0; GRID_Z],
            u: [0.0; GRID_Z],
        };
        Self {
            lo: z,
            hi: z,
            valid: false,
        }
    }
}

/// `acc += X[p]` (`sign` +1) or `acc -= X[p]` (-1) for padded row `p`, converting it on first use; all-zero
/// rows are skipped (exact f64 sums, so skipping zeros changes nothing).
#[inline(always)]
fn add_row(s: &mut SelectScratch, acc: &mut Row, p: usize, n: usize, w: f64) {
    match s.pad_state[p] {
        0 => return,
        1 => convert_row(s, p, n),
        _ => {}
    }
    let row: &Row = s.padded[p * GRID_Z..(p + 1) * GRID_Z].try_into().expect("a whole row");
    for c in 0..GRID_Z {
        acc[c] += w * row[c];
    }
}

/// Pass 1 (along elevation) at row `r` into `s.x`, rounded to f32 as the original's float matrix, with `R`
/// columns of azimuth wrap on each side (`x[R + c]` holds column `c`). Returns false, leaving `s.x` alone, when
/// every row of the window is zero (every smoothed value of the row is then +0).
///
/// A row next to the band already computed is stepped from the band's end: `T[r+1] = T[r] - L[r] + U[r]`,
/// `T[r-1] = T[r] + L[r-1] - U[r-1]`, with `L` and `U` stepped by one row in and one out. Every value is an exact
/// f64 sum (as everywhere in the smoothing), so stepping gives the same bits as summing the kernel afresh.
#[inline(always)]
fn pass1_row(s: &mut SelectScratch, band: &mut Band, r: usize, n: usize) -> bool {
    let window = r..=r + 2 * n;
    let all_zero = s.pad_state[window.clone()].iter().all(|&st| st == 0);
    if band.valid && r == band.hi.r + 1 {
        let mut h = band.hi;
        for c in 0..GRID_Z {
            h.t[c] += h.u[c] - h.l[c];
        }
        // L and U of row r: row r + R in and r - 1 out of L; r + 2R + 1 in and r + R out of U.
        add_row(s, &mut h.l, r + n, n, 1.0);
        add_row(s, &mut h.l, r - 1, n, -1.0);
        add_row(s, &mut h.u, r + 2 * n + 1, n, 1.0);
        add_row(s, &mut h.u, r + n, n, -1.0);
        h.r = r;
        band.hi = h;
    } else if band.valid && r + 1 == band.lo.r {
        let mut l = band.lo;
        add_row(s, &mut l.l, r, n, 1.0);
        add_row(s, &mut l.l, r + n + 1, n, -1.0);
        add_row(s, &mut l.u, r + n + 1, n, 1.0);
        add_row(s, &mut l.u, r + 2 * n + 2, n, -1.0);
        for c in 0..GRID_Z {
            l.t[c] += l.l[c] - l.u[c];
        }
        l.r = r;
        band.lo = l;
    } else {
        let mut f = RowSums {
            r,
            t: [0.0; GRID_Z],
            l: [0.0; GRID_Z],
            u: [0.0; GRID_Z],
        };
        for k in 0..=2 * n {
            let w = s.w[k];
            add_row(s, &mut f.t, r + k, n, w);
        }
        for k in 0..=n {
            add_row(s, &mut f.l, r + k, n, 1.0);
            add_row(s, &mut f.u, r + n + 1 + k, n, 1.0);
        }
        *band = Band {
            lo: f,
            hi: f,
            valid: true,
        };
    }
    if all_zero {
        return false;
    }
    let t = if band.hi.r == r { &band.hi.t } else { &band.lo.t };
    let inv = 1.0 / (n + 1) as f64;
    let pc = GRID_Z + 2 * n;
    // One spare element past the padding (read, never used, by `kernel_sums`).
    if s.x.len() < pc + 1 {
        s.x.resize(pc + 1, 0.0);
    }
    let x = &mut s.x[..pc];
    x[n..n + GRID_Z]
        .iter_mut()
        .zip(t)
        .for_each(|(o, &a)| *o = (a * inv) as f32 as f64);
    for c in 0..n {
        x[c] = x[GRID_Z + c];
        x[n + GRID_Z + c] = x[n + c];
    }
    true
}
