//! The averaging's work held within bounds on any flight. Soft-DTW and the landing cut's kernel cost grow
//! with the square of a flight's length (a 10,000 s flight's 20,000 bins would need gigabytes), so:
//!
//! - the average of one flight is the flight: there is nothing to align it with;
//! - series up to [`MAX_POINTS`] (600 s of 0.5 s bins, beyond the competition's 500 s simulation timeout)
//!   are averaged exactly as the reference libraries do; a longer one is averaged at that many points
//!   (stretched linearly over normalised time, as the barycenter's starting point is), and the barycenter
//!   stretched back to the longest flight's length, so DTW distances, sums along the alignment, keep the
//!   scale of the flights' own length;
//! - the landing cut of a longer average is searched on its means of consecutive blocks of points, at most
//!   [`MAX_POINTS`] of them, and placed back at the block's start.

use super::barycenter::{resample, soft_dtw_barycenter};
use super::dtw::Point3;
use super::landing::landing_cut;
use super::lbfgs::Options;
use super::softdtw::Series;

/// The longest series averaged (and landing-cut) exactly, points.
pub const MAX_POINTS: usize = 1200;

/// The barycenter of `series` ([`soft_dtw_barycenter`] within the bounds of the module); `None` as there.
pub fn barycenter(series: &[Series], gamma: f64, opt: Options) -> Option<Series> {
    if let [one] = series {
        return (!one.is_empty() && one.dim > 0).then(|| one.clone());
    }
    let longest = series.iter().map(Series::len).max()?;
    if longest <= MAX_POINTS {
        return soft_dtw_barycenter(series, gamma, opt);
    }
    if series.iter().any(Series::is_empty) {
        return None;
    }
    let short: Vec<Series> = (series.iter())
        .map(|s| {
            if s.len() > MAX_POINTS {
                resample(s, MAX_POINTS)
            } else {
                s.clone()
            }
        })
        .collect();
    let bary = soft_dtw_barycenter(&short, gamma, opt)?;
    Some(resample(&bary, longest))
}

/// Where the landing cut of `points` starts ([`landing_cut`] within the bounds of the module).
pub fn cut(points: &[Point3]) -> Option<usize> {
    if points.len() <= MAX_POINTS {
        return landing_cut(points);
    }
    let block = points.len().div_ceil(MAX_POINTS);
    let means: Vec<Point3> = points
        .chunks(block)
        .map(|c| {
            let n = c.len() as f64;
            let sum = c.iter().fold([0.0; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
            [sum[0] / n, sum[1] / n, sum[2] / n]
        })
        .collect();
    landing_cut(&means).map(|c| (c * block).min(points.len()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(values: Vec<f64>) -> Series {
        Series { dim: 1, values }
    }

    #[test]
    fn one_flight_is_its_own_average() {
        let s = series(vec![0.0, 1.0, 3.0, 6.0]);
        assert_eq!(barycenter(std::slice::from_ref(&s), 200.0, Options::default()), Some(s));
    }

    #[test]
    fn short_series_average_exactly_and_long_ones_keep_the_longest_length() {
        let a = series((0..50).map(f64::from).collect());
        let b = series((0..60).map(|i| f64::from(i) * 0.9).collect());
        let opt = Options::default();
        let exact = soft_dtw_barycenter(&[a.clone(), b.clone()], 200.0, opt);
        assert_eq!(barycenter(&[a, b], 200.0, opt), exact);
        let long = |n: usize, k: f64| series((0..n).map(|i| k * i as f64 / n as f64).collect());
        let avg = barycenter(&[long(5000, 100.0), long(4000, 90.0)], 200.0, opt).unwrap();
        assert_eq!(avg.len(), 5000);
        assert!((avg.values[4999] - 95.0).abs() < 5.0, "{}", avg.values[4999]);
    }

    #[test]
    fn a_long_flight_is_cut_where_it_lands() {
        // 3000 points flying at 10 m, then 1000 on the ground.
        let p: Vec<Point3> = (0..4000)
            .map(|i| {
                if i < 3000 {
                    [i as f64 * 0.1, 0.0, 10.0]
                } else {
                    [300.0, 0.0, 0.0]
                }
            })
            .collect();
        let c = cut(&p).unwrap();
        assert!((3000..=4000).contains(&c), "{c}");
    }
}
