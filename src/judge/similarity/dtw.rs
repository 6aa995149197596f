//! Dynamic time warping between two paths, as similaritymeasures' `dtw` computes it: the Euclidean
//! distance of aligned points, summed along the cheapest monotone alignment (steps right, down, diagonal).

/// A point of a path: `x` North, `y` East, `z` up, metres.
pub type Point3 = [f64; 3];

fn euclid(a: &Point3, b: &Point3) -> f64 {
    let (dx, dy, dz) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    (dx * dx + dy * dy + dz * dz).sqrt()
}

/// The DTW distance of two paths, metres (the sum of matched point distances); `None` if either is empty.
///
/// One row of the accumulated-cost matrix is kept, so memory is linear in the shorter path's length.
pub fn dtw(a: &[Point3], b: &[Point3]) -> Option<f64> {
    let (rows, cols) = if a.len() >= b.len() { (a, b) } else { (b, a) };
    if cols.is_empty() {
        return None;
    }
    let mut row = vec![0.0; cols.len()];
    let mut acc = 0.0;
    for (j, c) in cols.iter().enumerate() {
        acc += euclid(&rows[0], c);
        row[j] = acc;
    }
    for r in &rows[1..] {
        // `diag` is the previous row's value at j - 1, `row[j]` still the previous row's value at j.
        let mut diag = row[0];
        row[0] += euclid(r, &cols[0]);
        for j in 1..cols.len() {
            let up = row[j];
            let best = up.min(row[j - 1]).min(diag);
            diag = up;
            row[j] = euclid(r, &cols[j]) + best;
        }
    }
    row.last().copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn line(xs: &[f64]) -> Vec<Point3> {
        xs.iter().map(|&x| [x, 0.0, 0.0]).collect()
    }

    #[test]
    fn identical_paths_are_zero_apart() {
        let p = line(&[0.0, 1.0, 2.0, 5.0]);
        assert_eq!(dtw(&p, &p), Some(0.0));
    }

    #[test]
    fn a_repeated_point_costs_nothing_and_an_offset_costs_per_match() {
        assert_eq!(
            dtw(&line(&[0.0, 1.0, 2.0]), &line(&[0.0, 0.0, 1.0, 2.0, 2.0])),
            Some(0.0)
        );
        // Two points each matched to one point 3 m away.
        let a = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let b = vec![[0.0, 0.0, 3.0], [1.0, 0.0, 3.0]];
        assert_eq!(dtw(&a, &b), Some(6.0));
    }

    #[test]
    fn the_textbook_example() {
        // Hand computed: cost matrix |a_i - b_j| over a = 1,2,3 and b = 2,2,4 gives 1 + 0 + 0 + 1 = 2.
        assert_eq!(dtw(&line(&[1.0, 2.0, 3.0]), &line(&[2.0, 2.0, 4.0])), Some(2.0));
    }

    #[test]
    fn an_empty_path_has_no_distance() {
        assert_eq!(dtw(&[], &line(&[1.0])), None);
    }

    /// The quadratic definition, to check the one-row version against.
    fn dtw_full(a: &[Point3], b: &[Point3]) -> f64 {
        let (n, m) = (a.len(), b.len());
        let mut d = vec![vec![f64::INFINITY; m + 1]; n + 1];
        d[0][0] = 0.0;
        for i in 1..=n {
            for j in 1..=m {
                d[i][j] = euclid(&a[i - 1], &b[j - 1]) + d[i - 1][j].min(d[i][j - 1]).min(d[i - 1][j - 1]);
            }
        }
        d[n][m]
    }

    fn path() -> impl Strategy<Value = Vec<Point3>> {
        prop::collection::vec(prop::array::uniform3(-50.0..50.0f64), 1..25)
    }

    proptest! {
        #[test]
        fn matches_the_full_matrix_and_is_symmetric(a in path(), b in path()) {
            let d = dtw(&a, &b).unwrap();
            prop_assert!((d - dtw_full(&a, &b)).abs() <= 1e-9 * (1.0 + d));
            prop_assert!((d - dtw(&b, &a).unwrap()).abs() <= 1e-9 * (1.0 + d));
            prop_assert!(d >= 0.0);
        }
    }
}
