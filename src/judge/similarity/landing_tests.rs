use super::*;
use proptest::prelude::*;

/// A path flying north at 1 m per point for `flying` points, then standing still for `landed`.
fn fly_then_land(flying: usize, landed: usize) -> Vec<Point3> {
    let mut p: Vec<Point3> = (0..flying).map(|i| [i as f64, 0.0, 5.0]).collect();
    let last = [flying as f64, 0.0, 0.0];
    p.extend(std::iter::repeat_n(last, landed));
    p
}

#[test]
fn a_constant_segment_costs_just_under_the_penalty_per_extra_point() {
    // The clipped kernel of two equal points is exp(-0.01), so splitting a standing segment saves less
    // than the penalty and the search leaves it whole.
    let g = Gram::new(&fly_then_land(10, 10));
    let c = g.cost(10, 20);
    assert!((c - 9.0 * (1.0 - (-0.01f64).exp())).abs() < 1e-12, "{c}");
}

#[test]
fn the_last_segment_is_the_landed_one() {
    let p = fly_then_land(40, 30);
    let b = change_points(&p, LANDING_PENALTY);
    assert_eq!(*b.last().unwrap(), p.len());
    assert_eq!(b[b.len() - 2], 40, "{b:?}");
    assert_eq!(landing_cut(&p), Some(55));
}

#[test]
fn short_or_flat_paths_have_at_most_a_trivial_cut() {
    assert_eq!(change_points(&[[0.0; 3]], LANDING_PENALTY), vec![1]);
    assert_eq!(landing_cut(&[[0.0; 3]]), None);
    assert_eq!(change_points(&vec![[1.0, 2.0, 3.0]; 12], LANDING_PENALTY), vec![12]);
}

#[test]
fn numpy_median_of_an_even_count_is_the_middle_mean() {
    assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), Some(2.5));
    assert_eq!(median(&mut []), None);
}

/// The definition without pruning: every partition on the grid, best by total cost.
fn exhaustive(points: &[Point3], penalty: f64) -> f64 {
    let n = points.len();
    let g = Gram::new(points);
    let grid: Vec<usize> = (0..n)
        .step_by(JUMP)
        .filter(|&k| k >= MIN_SIZE)
        .chain(std::iter::once(n))
        .collect();
    let mut best: std::collections::BTreeMap<usize, f64> = [(0, 0.0)].into();
    for &end in &grid {
        let v = std::iter::once(0)
            .chain(grid.iter().copied().filter(|&t| t < end))
            .filter(|&t| end - t >= MIN_SIZE)
            .filter_map(|t| best.get(&t).map(|b| b + g.cost(t, end) + penalty))
            .fold(f64::INFINITY, f64::min);
        best.insert(end, v);
    }
    best[&n]
}

fn total(points: &[Point3], ends: &[usize], penalty: f64) -> f64 {
    let g = Gram::new(points);
    let mut start = 0;
    let mut sum = 0.0;
    for &e in ends {
        sum += g.cost(start, e) + penalty;
        start = e;
    }
    sum
}

proptest! {
    #[test]
    fn pruning_keeps_the_optimal_partition(
        points in prop::collection::vec(prop::array::uniform3(-20.0..20.0f64), 2..40),
        penalty in 0.001..2.0f64,
    ) {
        let ends = change_points(&points, penalty);
        prop_assert_eq!(*ends.last().unwrap(), points.len());
        prop_assert!(ends.windows(2).all(|w| w[0] < w[1]));
        let got = total(&points, &ends, penalty);
        prop_assert!((got - exhaustive(&points, penalty)).abs() < 1e-9, "{:?}", ends);
    }
}
