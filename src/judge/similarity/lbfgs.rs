//! Limited-memory BFGS for a smooth unconstrained objective, stopped the way scipy's L-BFGS-B stops
//! (tslearn's barycenter optimiser): at a small relative decrease, a small gradient, or an iteration cap.

/// When to stop and how much curvature to keep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Correction pairs kept (scipy's `maxcor`).
    pub memory: usize,
    /// Most iterations (scipy's `maxiter`).
    pub max_iter: usize,
    /// Stop when `(f_old - f) <= ftol * max(|f_old|, |f|, 1)` (scipy's `ftol`).
    pub ftol: f64,
    /// Stop when the largest gradient component is at most this (scipy's `gtol`).
    pub gtol: f64,
    /// Most objective evaluations in one line search (scipy's `maxls`).
    pub max_line_evals: usize,
}

impl Default for Options {
    /// scipy's `minimize(method="L-BFGS-B", tol=1e-3, options={"maxiter": 50})`, as tslearn calls it.
    fn default() -> Self {
        Self {
            memory: 10,
            max_iter: 50,
            ftol: 1e-3,
            gtol: 1e-3,
            max_line_evals: 20,
        }
    }
}

/// Sufficient decrease and curvature constants of the line search (MINPACK-2's `dcsrch` as L-BFGS-B uses it).
const C1: f64 = 1e-3;
const C2: f64 = 0.9;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p * q).sum()
}

fn inf_norm(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// A point with its value and gradient.
#[derive(Clone)]
struct At {
    x: Vec<f64>,
    f: f64,
    g: Vec<f64>,
}

/// Minimises `f` from `x0`. `f(x, grad)` returns the value and writes the gradient into `grad` (zeroed
/// before each call). Returns the last accepted point.
pub fn minimize(mut f: impl FnMut(&[f64], &mut [f64]) -> f64, x0: Vec<f64>, opt: Options) -> Vec<f64> {
    let mut eval = |x: Vec<f64>| {
        let mut g = vec![0.0; x.len()];
        let v = f(&x, &mut g);
        At { x, f: v, g }
    };
    let mut cur = eval(x0);
    let mut pairs: std::collections::VecDeque<(Vec<f64>, Vec<f64>)> = Default::default();
    for iter in 0..opt.max_iter {
        if !cur.f.is_finite() || inf_norm(&cur.g) <= opt.gtol {
            break;
        }
        let d = direction(&cur.g, &pairs);
        let slope = dot(&d, &cur.g);
        if slope >= 0.0 {
            break;
        }
        let first = if iter == 0 || pairs.is_empty() {
            (1.0 / dot(&d, &d).sqrt()).min(1e10)
        } else {
            1.0
        };
        let Some(next) = line_search(&mut eval, &cur, &d, slope, first, opt.max_line_evals) else {
            break;
        };
        let decrease = cur.f - next.f;
        let scale = cur.f.abs().max(next.f.abs()).max(1.0);
        let s: Vec<f64> = next.x.iter().zip(&cur.x).map(|(a, b)| a - b).collect();
        let y: Vec<f64> = next.g.iter().zip(&cur.g).map(|(a, b)| a - b).collect();
        cur = next;
        if decrease <= opt.ftol * scale {
            break;
        }
        if dot(&s, &y) > f64::EPSILON * dot(&y, &y) {
            if pairs.len() == opt.memory {
                pairs.pop_front();
            }
            pairs.push_back((s, y));
        }
    }
    cur.x
}

/// The two-loop recursion: `-H g` with the kept pairs, the initial `H` scaled by the newest pair.
fn direction(g: &[f64], pairs: &std::collections::VecDeque<(Vec<f64>, Vec<f64>)>) -> Vec<f64> {
    let mut q = g.to_vec();
    let mut alphas = Vec::with_capacity(pairs.len());
    for (s, y) in pairs.iter().rev() {
        let rho = 1.0 / dot(y, s);
        let a = rho * dot(s, &q);
        q.iter_mut().zip(y).for_each(|(qi, yi)| *qi -= a * yi);
        alphas.push((a, rho));
    }
    if let Some((s, y)) = pairs.back() {
        let h0 = dot(s, y) / dot(y, y);
        q.iter_mut().for_each(|v| *v *= h0);
    }
    for ((s, y), (a, rho)) in pairs.iter().zip(alphas.iter().rev()) {
        let b = rho * dot(y, &q);
        q.iter_mut().zip(s).for_each(|(qi, si)| *qi += (a - b) * si);
    }
    q.iter_mut().for_each(|v| *v = -*v);
    q
}

/// A step along `d` meeting the strong Wolfe conditions (bracketing, then zooming with cubic steps
/// kept inside the bracket); `None` if none is found within `max_evals` evaluations.
fn line_search(
    eval: &mut impl FnMut(Vec<f64>) -> At,
    from: &At,
    d: &[f64],
    slope0: f64,
    first: f64,
    max_evals: usize,
) -> Option<At> {
    let at = |eval: &mut dyn FnMut(Vec<f64>) -> At, step: f64| {
        let p = eval(from.x.iter().zip(d).map(|(x, di)| x + step * di).collect());
        let slope = dot(&p.g, d);
        (p, slope)
    };
    let (mut lo, mut lo_f, mut lo_slope) = (0.0, from.f, slope0);
    let mut hi: Option<(f64, f64, f64)> = None;
    let mut step = first;
    for _ in 0..max_evals {
        let (p, slope) = at(eval, step);
        let armijo = p.f <= from.f + C1 * step * slope0 && p.f.is_finite();
        if !armijo || p.f >= lo_f {
            hi = Some((step, p.f, slope));
        } else if slope.abs() <= -C2 * slope0 {
            return Some(p);
        } else {
            let flip = match hi {
                None => slope >= 0.0,
                Some((h, _, _)) => slope * (h - lo) >= 0.0,
            };
            if flip {
                hi = Some((lo, lo_f, lo_slope));
            }
            (lo, lo_f, lo_slope) = (step, p.f, slope);
        }
        step = match hi {
            None => step * 4.0,
            Some((h, h_f, h_slope)) => cubic_step(lo, lo_f, lo_slope, h, h_f, h_slope),
        };
    }
    None
}

/// The minimiser of the cubic through two points with slopes, kept in the middle 80 % of the bracket
/// (bisection when the cubic has none there).
fn cubic_step(a: f64, fa: f64, da: f64, b: f64, fb: f64, db: f64) -> f64 {
    let d1 = da + db - 3.0 * (fa - fb) / (a - b);
    let disc = d1 * d1 - da * db;
    let (left, right) = (a.min(b), a.max(b));
    let margin = 0.1 * (right - left);
    let mid = 0.5 * (a + b);
    if disc < 0.0 || !disc.is_finite() {
        return mid;
    }
    let d2 = (b - a).signum() * disc.sqrt();
    let t = b - (b - a) * (db + d2 - d1) / (db - da + 2.0 * d2);
    if t.is_finite() && t > left + margin && t < right - margin {
        t
    } else {
        mid
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rosenbrock(x: &[f64], g: &mut [f64]) -> f64 {
        let (a, b) = (x[0], x[1]);
        g[0] = -2.0 * (1.0 - a) - 400.0 * a * (b - a * a);
        g[1] = 200.0 * (b - a * a);
        (1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2)
    }

    #[test]
    fn finds_the_minimum_of_a_quadratic() {
        let x = minimize(
            |x, g| {
                g[0] = 2.0 * (x[0] - 3.0);
                g[1] = 20.0 * (x[1] + 1.0);
                (x[0] - 3.0).powi(2) + 10.0 * (x[1] + 1.0).powi(2)
            },
            vec![0.0, 0.0],
            Options {
                ftol: 0.0,
                gtol: 1e-9,
                ..Options::default()
            },
        );
        assert!((x[0] - 3.0).abs() < 1e-6 && (x[1] + 1.0).abs() < 1e-6, "{x:?}");
    }

    #[test]
    fn walks_down_the_rosenbrock_valley() {
        let tight = Options {
            ftol: 0.0,
            gtol: 1e-8,
            max_iter: 500,
            ..Options::default()
        };
        let x = minimize(rosenbrock, vec![-1.2, 1.0], tight);
        assert!((x[0] - 1.0).abs() < 1e-4 && (x[1] - 1.0).abs() < 1e-4, "{x:?}");
    }

    #[test]
    fn the_iteration_cap_stops_early() {
        let capped = Options {
            ftol: 0.0,
            gtol: 0.0,
            max_iter: 1,
            ..Options::default()
        };
        let x = minimize(rosenbrock, vec![-1.2, 1.0], capped);
        assert!(
            (x[0] - 1.0).abs() > 0.1,
            "one iteration cannot reach the minimum: {x:?}"
        );
    }
}
