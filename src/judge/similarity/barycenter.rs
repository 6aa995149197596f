//! The soft-DTW barycenter of several series (tslearn's `softdtw_barycenter`): start from the pointwise
//! mean of the series stretched to the longest one's length, then minimise the mean soft-DTW to them.

use super::lbfgs::{Options, minimize};
use super::softdtw::{Series, soft_dtw_grad};

/// `s` stretched or shrunk to `len` points by linear interpolation over normalised time (both ends kept).
pub fn resample(s: &Series, len: usize) -> Series {
    let n = s.len();
    let mut values = Vec::with_capacity(len * s.dim);
    for i in 0..len {
        let u = if len > 1 { i as f64 / (len - 1) as f64 } else { 0.0 };
        let pos = u * n.saturating_sub(1) as f64;
        let lo = (pos.floor() as usize).min(n - 1);
        let hi = (lo + 1).min(n - 1);
        let frac = pos - lo as f64;
        for k in 0..s.dim {
            let (a, b) = (s.point(lo)[k], s.point(hi)[k]);
            values.push(if hi == lo { a } else { a + frac * (b - a) });
        }
    }
    Series { dim: s.dim, values }
}

/// The pointwise mean of the series after stretching each to the longest length.
pub fn stretched_mean(series: &[Series]) -> Option<Series> {
    let first = series.first()?;
    let len = series.iter().map(Series::len).max()?;
    if len == 0 || series.iter().any(|s| s.is_empty() || s.dim != first.dim) {
        return None;
    }
    let mut values = vec![0.0; len * first.dim];
    let w = 1.0 / series.len() as f64;
    for s in series {
        for (acc, v) in values.iter_mut().zip(resample(s, len).values) {
            *acc += w * v;
        }
    }
    Some(Series { dim: first.dim, values })
}

/// The soft-DTW barycenter with smoothing `gamma`, as long as the longest series; `None` without series,
/// with an empty one, or with series of different dimensions.
pub fn soft_dtw_barycenter(series: &[Series], gamma: f64, opt: Options) -> Option<Series> {
    let init = stretched_mean(series)?;
    let dim = init.dim;
    let w = 1.0 / series.len() as f64;
    let objective = |z: &[f64], grad: &mut [f64]| {
        let zs = Series {
            dim,
            values: z.to_vec(),
        };
        series.iter().map(|x| w * soft_dtw_grad(&zs, x, gamma, w, grad)).sum()
    };
    let values = minimize(objective, init.values, opt);
    Some(Series { dim, values })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(values: &[f64]) -> Series {
        Series {
            dim: 1,
            values: values.to_vec(),
        }
    }

    #[test]
    fn resampling_keeps_the_ends_and_interpolates_between() {
        let r = resample(&series(&[0.0, 10.0]), 5);
        assert_eq!(r.values, vec![0.0, 2.5, 5.0, 7.5, 10.0]);
        assert_eq!(resample(&series(&[3.0]), 3).values, vec![3.0, 3.0, 3.0]);
    }

    #[test]
    fn the_starting_point_is_the_mean_of_the_stretched_series() {
        let m = stretched_mean(&[series(&[0.0, 2.0, 4.0]), series(&[2.0, 6.0])]).unwrap();
        assert_eq!(m.values, vec![1.0, 3.0, 5.0]);
    }

    #[test]
    fn mismatched_or_empty_series_have_no_barycenter() {
        let two_d = Series {
            dim: 2,
            values: vec![0.0, 0.0],
        };
        assert!(soft_dtw_barycenter(&[series(&[1.0]), two_d], 1.0, Options::default()).is_none());
        assert!(soft_dtw_barycenter(&[series(&[])], 1.0, Options::default()).is_none());
        assert!(soft_dtw_barycenter(&[], 1.0, Options::default()).is_none());
    }

    /// tslearn's documented example: `softdtw_barycenter([[1, 2, 3, 4], [1, 2, 4, 5]], max_iter=5)`
    /// gives 1.2516, 2.0382, 3.5102, 4.3614 (gamma 1).
    #[test]
    fn reproduces_the_reference_example_closely() {
        let opt = Options {
            max_iter: 5,
            ..Options::default()
        };
        let b = soft_dtw_barycenter(
            &[series(&[1.0, 2.0, 3.0, 4.0]), series(&[1.0, 2.0, 4.0, 5.0])],
            1.0,
            opt,
        )
        .unwrap();
        let want = [1.25161574, 2.03821705, 3.5101956, 4.36140605];
        for (got, want) in b.values.iter().zip(want) {
            assert!((got - want).abs() < 0.05, "{:?}", b.values);
        }
    }

    #[test]
    fn identical_series_average_to_a_close_copy() {
        let s = series(&[0.0, 1.0, 3.0, 6.0, 10.0, 10.0]);
        let b = soft_dtw_barycenter(&[s.clone(), s.clone(), s.clone()], 0.1, Options::default()).unwrap();
        for (got, want) in b.values.iter().zip(&s.values) {
            assert!((got - want).abs() < 0.5, "{:?}", b.values);
        }
    }
}
