//! The 2026 evaluation's trajectory work: one test's average (soft-DTW barycenter of 5 flights and the
//! landing cut) and one DTW distance between two averages, on flights of a typical 60 s mission.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use prgenuav::judge::similarity::{average, path_distance, prepare};
use prgenuav::model::{Sample, Trajectory};

/// A 60 s S-shaped flight at 10 Hz, swaying by `sway` metres, then 10 s on the ground.
fn flight(sway: f64) -> Trajectory {
    let samples = (0..700)
        .map(|i| {
            let t = f64::from(i) / 10.0;
            let s = t.min(60.0) / 60.0;
            Sample {
                t_s: t,
                x: 50.0 * s,
                y: (sway + 5.0) * (s * std::f64::consts::TAU).sin(),
                z: if t < 60.0 { 10.0 } else { 0.0 },
                r: Some(0.0),
            }
        })
        .collect();
    Trajectory::new(samples)
}

fn similarity(c: &mut Criterion) {
    let flights: Vec<Trajectory> = (0..5).map(|k| prepare(&flight(0.2 * f64::from(k)))).collect();
    let a = average(&flights).expect("average");
    let b = average(&flights[1..]).expect("average");
    let mut group = c.benchmark_group("similarity");
    group.sample_size(10);
    group.bench_function("average_of_5_flights", |bench| {
        bench.iter(|| black_box(average(black_box(&flights))))
    });
    group.bench_function("dtw_of_two_averages", |bench| {
        bench.iter(|| black_box(path_distance(&a, &b)))
    });
    group.finish();
}

criterion_group!(benches, similarity);
criterion_main!(benches);
