//! Criterion benches of the failure-probability ensemble: N = 8 members of one two-obstacle mission-2
//! candidate on one thread (screening runs one candidate per core, so candidates per second on 2 cores is
//! 2 / this median), beside the plain N = 1 `simulate` of the same candidate.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use prgenuav::lfs::ensemble::{EnsembleParams, run_ensemble};
use prgenuav::lfs::sim::{SimConfig, simulate};
use prgenuav::model::{Obstacle, TestCase};

fn candidate() -> TestCase {
    TestCase::load(Path::new("missions/mission2.yaml"))
        .expect("missions/mission2.yaml (run from the crate root)")
        .with_obstacles(vec![
            Obstacle::new(10.0, 5.0, 20.0, 10.0, 20.0, 0.0),
            Obstacle::new(10.0, 5.0, 20.0, -10.0, 20.0, 0.0),
        ])
}

fn bench(c: &mut Criterion) {
    let test = candidate();
    let config = SimConfig::default();
    let params = EnsembleParams::default();
    let mut g = c.benchmark_group("ensemble");
    g.sample_size(10);
    g.bench_function("simulate N=1, mission 2 candidate", |b| {
        b.iter(|| black_box(simulate(&test, &config).expect("simulates").cycles))
    });
    g.bench_function("ensemble N=8, mission 2 candidate, 1 thread", |b| {
        b.iter(|| {
            let e =
                run_ensemble(&test.mission, &test.obstacles, &test.params, &config, &params, 8, 0, 1).expect("runs");
            black_box(e.member_min_distances.len())
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
