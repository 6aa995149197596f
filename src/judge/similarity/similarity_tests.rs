use super::*;

/// A flight north along `y = offset` at 2 m/s for `secs`, climbing to 5 m, then landed for 10 s;
/// samples every 0.1 s.
fn flight(offset: f64, secs: f64) -> Trajectory {
    let mut samples = Vec::new();
    let total = secs + 10.0;
    let mut t = 0.0;
    while t <= total {
        let flying = t <= secs;
        let x = 2.0 * t.min(secs);
        samples.push(Sample {
            t_s: t,
            x,
            y: offset,
            z: if flying { 5.0f64.min(t) } else { 0.0 },
            r: Some(0.0),
        });
        t += 0.1;
    }
    Trajectory::new(samples)
}

#[test]
fn preparing_aligns_the_origin_and_bins_half_seconds() {
    let p = prepare(&flight(3.0, 10.0));
    // The first bin holds 0 to 0.5 s: the mean of the first half second, the east offset gone.
    assert_eq!(p.samples[0].y, 0.0);
    assert!((p.samples[0].x - 0.5).abs() < 1e-9, "{:?}", p.samples[0]);
    let dt = p.samples[2].t_s - p.samples[1].t_s;
    assert!((dt - 0.5).abs() < 0.1, "{dt}");
}

#[test]
fn the_average_of_copies_follows_them_and_lands_in_one_point() {
    let f = prepare(&flight(0.0, 20.0));
    let avg = average(&[f.clone(), f.clone(), f.clone()]).unwrap();
    // The landed 10 s are 20 bins: the cut is in the middle of them, the second half becomes one point.
    let dropped = f.samples.len() - avg.samples.len();
    assert!(
        (8..=11).contains(&dropped),
        "{} vs {}",
        avg.samples.len(),
        f.samples.len()
    );
    let end = avg.samples.last().unwrap();
    assert!((end.x - 40.0).abs() < 1.0 && end.z.abs() < 1.0, "{end:?}");
    let d = path_distance(&avg, &f).unwrap();
    let far = path_distance(&avg, &prepare(&flight(0.0, 10.0))).unwrap();
    assert!(d < far, "{d} vs {far}");
}

#[test]
fn averages_of_different_routes_lie_farther_apart_than_of_the_same_route() {
    let same_a = average(&[prepare(&flight(0.0, 20.0)), prepare(&flight(0.0, 21.0))]).unwrap();
    let same_b = average(&[prepare(&flight(0.0, 20.5)), prepare(&flight(0.0, 19.5))]).unwrap();
    let other = average(&[prepare(&flight(0.0, 12.0)), prepare(&flight(0.0, 12.5))]).unwrap();
    let near = path_distance(&same_a, &same_b).unwrap();
    let far = path_distance(&same_a, &other).unwrap();
    assert!(near * 3.0 < far, "{near} vs {far}");
}

#[test]
fn no_flights_no_average() {
    assert!(average(&[]).is_none());
    assert!(average(&[Trajectory::default()]).is_none());
    assert!(path_distance(&Trajectory::default(), &flight(0.0, 1.0)).is_none());
}

#[test]
fn headings_survive_only_when_every_flight_has_them() {
    let mut f = prepare(&flight(0.0, 5.0));
    assert!(average(std::slice::from_ref(&f)).unwrap().samples[0].r.is_some());
    f.samples[3].r = None;
    assert!(average(&[f]).unwrap().samples.iter().all(|s| s.r.is_none()));
}

#[test]
fn the_average_of_flights_of_different_lengths_never_runs_back_in_time() {
    // The barycenter of these times alone runs back by 166 s.
    for (a, b) in [(60.0, 300.0)] {
        let avg = average(&[prepare(&flight(0.0, a)), prepare(&flight(1.0, b))]).unwrap();
        for w in avg.samples.windows(2) {
            assert!(w[1].t_s >= w[0].t_s, "{a} s and {b} s: {} after {}", w[1].t_s, w[0].t_s);
        }
    }
}
