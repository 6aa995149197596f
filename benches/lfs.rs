//! Criterion benches of the low-fidelity simulator: one planner cycle including the render (target: median at
//! most 0.5 ms on one core), its render alone, and one whole `simulate` of a two-obstacle test on mission 2
//! (target: at most 0.5 s).

use std::hint::black_box;
use std::path::Path;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use prgenuav::lfs::camera::Camera;
use prgenuav::lfs::render::CameraPose;
use prgenuav::lfs::render_fast::{FastRenderScratch, KeepRange, render_cloud};
use prgenuav::lfs::sim::{SimConfig, World, simulate, step};
use prgenuav::model::{Obstacle, TestCase};

fn two_obstacle_test() -> TestCase {
    TestCase::load(Path::new("missions/mission2.yaml"))
        .expect("missions/mission2.yaml (run from the crate root)")
        .with_obstacles(vec![
            Obstacle::new(10.0, 5.0, 20.0, 10.0, 20.0, 0.0),
            Obstacle::new(10.0, 5.0, 20.0, -10.0, 20.0, 0.0),
        ])
}

/// A world flown to `t_s` seconds: cruising towards the obstacles with a filled point memory.
fn world_at(t_s: f64) -> World {
    let mut w = World::new(&two_obstacle_test(), SimConfig::default()).expect("valid test");
    while w.time_s < t_s {
        step(&mut w, 0.1);
    }
    w
}

fn bench(c: &mut Criterion) {
    let test = two_obstacle_test();
    let world = world_at(14.0);
    c.bench_function(
        "lfs/cycle (render + cloud + tree + motion), mission 2 near obstacles",
        |b| {
            b.iter_batched(
                || world.clone(),
                |mut w| black_box(step(&mut w, 0.1)),
                BatchSize::SmallInput,
            )
        },
    );
    let scene = prgenuav::lfs::render::Scene::new(&test.obstacles);
    let cam = Camera::hfs();
    let pose = CameraPose::level(world.vehicle.position_enu, world.vehicle.yaw_enu_rad);
    let keep = KeepRange {
        min_m: 0.2,
        max_m: 15.0,
    };
    let mut scratch = FastRenderScratch::default();
    let mut out = Vec::new();
    c.bench_function("lfs/render (fast path, 640x480 camera)", |b| {
        b.iter(|| {
            out.clear();
            render_cloud(&scene, &cam, &pose, keep, &mut scratch, &mut out).expect("valid pose");
            black_box(out.len())
        })
    });
    let config = SimConfig::default();
    let mut g = c.benchmark_group("lfs/simulate");
    g.sample_size(10);
    g.bench_function("mission 2, two obstacles, paper motion", |b| {
        b.iter(|| black_box(simulate(&test, &config).expect("simulates").cycles))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
