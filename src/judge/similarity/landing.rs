//! The landing cut of an average trajectory: a penalised change-point search (PELT with the RBF-kernel
//! cost, as ruptures' `Pelt(model="rbf")`) finds the last change; the points after the middle of the last
//! segment are replaced by their mean, so the time spent standing on the ground does not count twice.

use super::dtw::Point3;

/// Aerialist's penalty per change point.
pub const LANDING_PENALTY: f64 = 0.01;
/// ruptures' defaults: the shortest segment and the grid change points are searched on.
const MIN_SIZE: usize = 2;
const JUMP: usize = 5;
/// ruptures clips the scaled squared distances to this range before the exponential.
const CLIP: (f64, f64) = (1e-2, 1e2);

/// The RBF Gram matrix with the median heuristic, as cumulative sums for O(1) block sums.
struct Gram {
    n: usize,
    /// `cum[(i) * (n + 1) + j]` = sum of `k[a][b]` for `a < i`, `b < j`.
    cum: Vec<f64>,
}

impl Gram {
    fn new(points: &[Point3]) -> Self {
        let n = points.len();
        let sq = |a: &Point3, b: &Point3| (0..3).map(|k| (a[k] - b[k]) * (a[k] - b[k])).sum::<f64>();
        let mut pairs = Vec::with_capacity(n * n.saturating_sub(1) / 2);
        for i in 0..n {
            for j in i + 1..n {
                pairs.push(sq(&points[i], &points[j]));
            }
        }
        let median = median(&mut pairs.clone());
        let gamma = if median.is_some_and(|m| m != 0.0) {
            1.0 / median.unwrap_or(1.0)
        } else {
            1.0
        };
        let mut k = vec![1.0; n * n];
        let mut idx = 0;
        for i in 0..n {
            for j in i + 1..n {
                let v = (-(pairs[idx] * gamma).clamp(CLIP.0, CLIP.1)).exp();
                k[i * n + j] = v;
                k[j * n + i] = v;
                idx += 1;
            }
        }
        let w = n + 1;
        let mut cum = vec![0.0; w * w];
        for i in 0..n {
            for j in 0..n {
                cum[(i + 1) * w + j + 1] = k[i * n + j] + cum[i * w + j + 1] + cum[(i + 1) * w + j] - cum[i * w + j];
            }
        }
        Self { n, cum }
    }

    /// ruptures' RBF segment cost of `start..end`: its length minus the block's kernel sum over its length.
    fn cost(&self, start: usize, end: usize) -> f64 {
        let w = self.n + 1;
        let block = self.cum[end * w + end] - self.cum[start * w + end] - self.cum[end * w + start]
            + self.cum[start * w + start];
        (end - start) as f64 - block / (end - start) as f64
    }
}

/// numpy's median (the mean of the two middle values for an even count); `None` when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// PELT's optimal segmentation at `penalty`: the sorted segment ends, the last one `points.len()`.
/// Change points lie on multiples of 5 with segments of at least 2 points; fewer than 2 points give `[n]`.
pub fn change_points(points: &[Point3], penalty: f64) -> Vec<usize> {
    let n = points.len();
    if n < MIN_SIZE {
        return vec![n];
    }
    let gram = Gram::new(points);
    // best[t]: (total cost of the best partition of ..t, its previous end).
    let mut best: std::collections::BTreeMap<usize, (f64, usize)> = [(0, (0.0, 0))].into();
    let mut admissible: Vec<usize> = Vec::new();
    let ends = (0..n)
        .step_by(JUMP)
        .filter(|&k| k >= MIN_SIZE)
        .chain(std::iter::once(n));
    for end in ends {
        admissible.push((end - MIN_SIZE) / JUMP * JUMP);
        let totals: Vec<Option<f64>> = admissible
            .iter()
            .map(|t| best.get(t).map(|(total, _)| total + (gram.cost(*t, end) + penalty)))
            .collect();
        let mut pick: Option<(f64, usize)> = None;
        for (t, total) in admissible.iter().zip(&totals) {
            if let Some(v) = total
                && pick.is_none_or(|(b, _)| *v < b)
            {
                pick = Some((*v, *t));
            }
        }
        let Some((bound, from)) = pick else { continue };
        best.insert(end, (bound, from));
        let keep: Vec<usize> = admissible
            .iter()
            .zip(&totals)
            .filter(|(_, v)| v.is_some_and(|v| v <= bound + penalty))
            .map(|(t, _)| *t)
            .collect();
        admissible = keep;
    }
    let mut out = Vec::new();
    let mut end = n;
    while end > 0 {
        out.push(end);
        end = best.get(&end).map_or(0, |(_, from)| *from);
    }
    out.reverse();
    out
}

/// Where the landing cut starts: the middle of the last segment, `None` with fewer than two segments.
pub fn landing_cut(points: &[Point3]) -> Option<usize> {
    let b = change_points(points, LANDING_PENALTY);
    (b.len() >= 2).then(|| (b[b.len() - 2] + b[b.len() - 1]) / 2)
}

#[cfg(test)]
#[path = "landing_tests.rs"]
mod tests;
