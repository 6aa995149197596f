//! The 2026 evaluation's trajectory work: one test's average (soft-DTW barycenter of 5 flights and the
//! landing cut) and one DTW distance between two averages, on flights of a typical 60 s mission; and the
//! average of very long flights, whose work is bounded (one flight of 10^6 samples over 10,000 s, five of
//! 2,400 s).

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

/// A `secs` long flight of `n` samples swaying east and west, then landed for the last 1 %.
fn long_flight(n: u32, secs: f64, sway: f64) -> Trajectory {
    let samples = (0..n)
        .map(|i| {
            let t = secs * f64::from(i) / f64::from(n);
            let s = t / secs;
            Sample {
                t_s: t,
                x: 50.0 * (s * 40.0 * std::f64::consts::PI).sin(),
                y: 10.0 + 20.0 * s + sway,
                z: if s < 0.99 { 10.0 } else { 0.0 },
                r: Some(0.0),
            }
        })
        .collect();
    Trajectory::new(samples)
}

fn long_flights(c: &mut Criterion) {
    let one = long_flight(1_000_000, 10_000.0, 0.0);
    let five: Vec<Trajectory> = (0..5)
        .map(|k| prepare(&long_flight(24_000, 2400.0, f64::from(k))))
        .collect();
    let mut group = c.benchmark_group("similarity_long");
    group.sample_size(10);
    group.bench_function("average_of_one_flight_of_1e6_samples", |bench| {
        bench.iter(|| black_box(average(&[prepare(black_box(&one))])))
    });
    group.bench_function("average_of_5_flights_of_2400_s", |bench| {
        bench.iter(|| black_box(average(black_box(&five))))
    });
    group.finish();
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

criterion_group!(benches, similarity, long_flights);
criterion_main!(benches);
