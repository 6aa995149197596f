//! Soft-DTW (Cuturi and Blondel, 2017) between two multivariate series and its gradient with respect to
//! the first, on squared Euclidean point costs: the objective a soft-DTW barycenter minimises.

/// A series of `len` points of `dim` values each, stored row by row.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Values per point.
    pub dim: usize,
    /// `len x dim` values, point after point.
    pub values: Vec<f64>,
}

impl Series {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.values.len().checked_div(self.dim).unwrap_or(0)
    }

    /// Whether the series has no point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Point `i`.
    pub fn point(&self, i: usize) -> &[f64] {
        &self.values[i * self.dim..(i + 1) * self.dim]
    }
}

/// The smooth minimum `-gamma log sum exp(-v / gamma)` of three values, stable for large arguments.
fn softmin3(a: f64, b: f64, c: f64, gamma: f64) -> f64 {
    let (a, b, c) = (-a / gamma, -b / gamma, -c / gamma);
    let m = a.max(b).max(c);
    -gamma * (((a - m).exp() + (b - m).exp() + (c - m).exp()).ln() + m)
}

fn sq_dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum()
}

/// Soft-DTW of `z` against `x` with smoothing `gamma` (> 0); adds `weight` times its gradient with
/// respect to `z`'s values into `grad` (same layout as `z.values`) and returns the value.
pub fn soft_dtw_grad(z: &Series, x: &Series, gamma: f64, weight: f64, grad: &mut [f64]) -> f64 {
    let (m, n) = (z.len(), x.len());
    let w = n + 2;
    // Cost matrix padded with a zero row and column past the end, as the backward pass reads them.
    let mut d = vec![0.0; (m + 1) * (n + 1)];
    for i in 0..m {
        for j in 0..n {
            d[i * (n + 1) + j] = sq_dist(z.point(i), x.point(j));
        }
    }
    let dij = |i: usize, j: usize| d[i * (n + 1) + j];
    // Forward pass: r[i][j] is the soft alignment cost of z[..i] with x[..j].
    let mut r = vec![0.0; (m + 2) * w];
    r[1..=n].fill(f64::INFINITY);
    for i in 1..=m {
        r[i * w] = f64::INFINITY;
        for j in 1..=n {
            let best = softmin3(r[(i - 1) * w + j], r[(i - 1) * w + j - 1], r[i * w + j - 1], gamma);
            r[i * w + j] = dij(i - 1, j - 1) + best;
        }
    }
    let value = r[m * w + n];
    // Backward pass: e[i][j] is the derivative of the value with respect to the cost of cell (i, j).
    for i in 1..=m {
        r[i * w + n + 1] = f64::NEG_INFINITY;
    }
    for j in 1..=n {
        r[(m + 1) * w + j] = f64::NEG_INFINITY;
    }
    r[(m + 1) * w + n + 1] = value;
    let mut e = vec![0.0; (m + 2) * w];
    e[(m + 1) * w + n + 1] = 1.0;
    for j in (1..=n).rev() {
        for i in (1..=m).rev() {
            if r[i * w + j] == f64::INFINITY {
                r[i * w + j] = f64::NEG_INFINITY;
            }
            let here = r[i * w + j];
            let a = ((r[(i + 1) * w + j] - here - dij(i, j - 1)) / gamma).exp();
            let b = ((r[i * w + j + 1] - here - dij(i - 1, j)) / gamma).exp();
            let c = ((r[(i + 1) * w + j + 1] - here - dij(i, j)) / gamma).exp();
            e[i * w + j] = e[(i + 1) * w + j] * a + e[i * w + j + 1] * b + e[(i + 1) * w + j + 1] * c;
        }
    }
    chain_rule(z, x, &e, weight, grad);
    value
}

/// Adds `weight` times the gradient with respect to `z` of the squared Euclidean costs weighted by `e`
/// (the backward pass's `(m + 2) x (n + 2)` matrix) into `grad`.
fn chain_rule(z: &Series, x: &Series, e: &[f64], weight: f64, grad: &mut [f64]) {
    let (m, n, dim) = (z.len(), x.len(), z.dim);
    let w = n + 2;
    for i in 0..m {
        let zi = z.point(i);
        for j in 0..n {
            let eij = e[(i + 1) * w + j + 1];
            if eij == 0.0 {
                continue;
            }
            let xj = x.point(j);
            for k in 0..dim {
                grad[i * dim + k] += weight * eij * 2.0 * (zi[k] - xj[k]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn series(values: &[f64]) -> Series {
        Series {
            dim: 1,
            values: values.to_vec(),
        }
    }

    #[test]
    fn small_gamma_approaches_the_hard_dtw_of_squared_costs() {
        let (z, x) = (series(&[1.0, 2.0, 3.0]), series(&[2.0, 2.0, 4.0]));
        let mut g = vec![0.0; 3];
        // Hard DTW on squared costs: 1 + 0 + 0 + 1 = 2.
        let v = soft_dtw_grad(&z, &x, 1e-3, 1.0, &mut g);
        assert!((v - 2.0).abs() < 1e-2, "{v}");
    }

    #[test]
    fn one_point_each_is_the_squared_distance() {
        let mut g = vec![0.0; 2];
        let z = Series {
            dim: 2,
            values: vec![1.0, 2.0],
        };
        let x = Series {
            dim: 2,
            values: vec![4.0, 6.0],
        };
        assert!((soft_dtw_grad(&z, &x, 10.0, 1.0, &mut g) - 25.0).abs() < 1e-12);
        assert!((g[0] + 6.0).abs() < 1e-12 && (g[1] + 8.0).abs() < 1e-12, "{g:?}");
    }

    proptest! {
        #[test]
        fn the_gradient_matches_finite_differences(
            z in prop::collection::vec(-5.0..5.0f64, 2..8),
            x in prop::collection::vec(-5.0..5.0f64, 1..8),
            gamma in 0.1..300.0f64,
        ) {
            let (zs, xs) = (series(&z), series(&x));
            let mut g = vec![0.0; z.len()];
            soft_dtw_grad(&zs, &xs, gamma, 1.0, &mut g);
            for (k, gk) in g.iter().enumerate() {
                let h = 1e-5;
                let mut plus = zs.clone();
                plus.values[k] += h;
                let mut minus = zs.clone();
                minus.values[k] -= h;
                let mut scratch = vec![0.0; z.len()];
                let fd = (soft_dtw_grad(&plus, &xs, gamma, 1.0, &mut scratch)
                    - soft_dtw_grad(&minus, &xs, gamma, 1.0, &mut scratch)) / (2.0 * h);
                prop_assert!((fd - gk).abs() <= 1e-4 * (1.0 + fd.abs()), "k {k}: {fd} vs {gk}");
            }
        }
    }
}
