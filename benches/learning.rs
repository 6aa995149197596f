//! The learning campaign's per-round cost that grows with the flights: choosing the flights' kernel by
//! leave-one-out (25 kernels x n^2), then predicting a round's candidates with it.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use prgenuav::campaign::learn::surrogate::{KernelPoint, Surrogate};

/// `n` flights spread over the unit draws, a smooth truth the LFS partly misses (deterministic).
fn flights(n: usize) -> Vec<KernelPoint> {
    (0..n)
        .map(|i| {
            let unit = std::array::from_fn(|d| ((i * (2 * d + 3) + d) % 97) as f64 / 97.0);
            let flown_m = 1.2 + unit[2] + 0.5 * unit[3];
            KernelPoint {
                unit,
                lfs_m: 1.6 + 0.3 * unit[2],
                flown_m,
            }
        })
        .collect()
}

fn learning(c: &mut Criterion) {
    let mut group = c.benchmark_group("learning");
    for n in [25, 100] {
        let f = flights(n);
        group.bench_function(format!("kernel_fit_{n}_flights"), |b| {
            b.iter(|| black_box(Surrogate::fit(black_box(&f))))
        });
    }
    let f = flights(100);
    let k = Surrogate::fit(&f).expect("the kernel beats this LFS");
    let candidates = flights(900);
    group.bench_function("predict_900_candidates_from_100_flights", |b| {
        b.iter(|| {
            candidates
                .iter()
                .map(|c| k.predict(&c.unit, c.lfs_m, black_box(&f)))
                .sum::<f64>()
        })
    });
    group.finish();
}

criterion_group!(benches, learning);
criterion_main!(benches);
