//! Sampling throughput of the generator: one valid test (draws + every rule check) per iteration.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use prgenuav::generator::{Generator, GeneratorConfig};
use prgenuav::model::TestCase;

fn sampling(c: &mut Criterion) {
    let mut group = c.benchmark_group("generator");
    group.throughput(Throughput::Elements(1));
    for n in [1, 2, 3] {
        let case = TestCase::load(Path::new(&format!("missions/mission{n}.yaml"))).expect("case study");
        let g = Generator::new(&case, GeneratorConfig::default(), 1).expect("generator");
        let mut i = 0u64;
        group.bench_function(format!("sample_mission{n}"), |b| {
            b.iter(|| {
                i += 1;
                black_box(g.sample(black_box(i)).expect("valid test"))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, sampling);
criterion_main!(benches);
