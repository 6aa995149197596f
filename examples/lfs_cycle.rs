//! Profiling harness for one planner cycle (the state of `benches/lfs.rs`): run under
//! `valgrind --tool=callgrind --toggle-collect=lfs_cycle::cycles` to count the instructions of N cycles.
//!
//! It prints FNV digests of the tree, the point memory and the vehicle after the cycle (equal digests mean
//! bit-identical results); `LFS_CYCLE_FLIGHT=1` adds the digest of a whole flight's trajectory, and
//! `LFS_CYCLE_TIME=1` prints wall-clock medians instead (a quick A/B check; criterion gives the real numbers).
//!
//! `cargo run --release --example lfs_cycle -- [N=10]`

use std::hint::black_box;
use std::path::Path;

use prgenuav::lfs::sim::{SimConfig, World, step};
use prgenuav::model::{Obstacle, TestCase};

/// The bench's world: mission 2 with two boxes, flown to `t_s` seconds.
fn world_at(t_s: f64) -> World {
    let test = TestCase::load(Path::new("missions/mission2.yaml"))
        .expect("missions/mission2.yaml (run from the crate root)")
        .with_obstacles(vec![
            Obstacle::new(10.0, 5.0, 20.0, 10.0, 20.0, 0.0),
            Obstacle::new(10.0, 5.0, 20.0, -10.0, 20.0, 0.0),
        ]);
    let mut w = World::new(&test, SimConfig::default()).expect("valid test");
    while w.time_s < t_s {
        step(&mut w, 0.1);
    }
    w
}

/// Runs one cycle on each world (the only code callgrind should count).
#[inline(never)]
fn cycles(worlds: &mut [World]) {
    for w in worlds {
        black_box(step(w, 0.1));
    }
}

/// Wall-clock medians (microseconds) of one cycle on a fresh clone: stepped right after cloning (warm), after
/// cloning a batch of 64 (as criterion's `iter_batched`), and the drop of a stepped world.
fn timings(world: &World) {
    use std::time::Instant;
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (mut warm, mut batched, mut drops) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..30 {
        for _ in 0..64 {
            let mut w = world.clone();
            let t = Instant::now();
            black_box(step(&mut w, 0.1));
            warm.push(t.elapsed().as_secs_f64() * 1e6);
            let t = Instant::now();
            drop(black_box(w));
            drops.push(t.elapsed().as_secs_f64() * 1e6);
        }
        let mut ws: Vec<World> = (0..64).map(|_| world.clone()).collect();
        for w in &mut ws {
            let t = Instant::now();
            black_box(step(w, 0.1));
            batched.push(t.elapsed().as_secs_f64() * 1e6);
        }
    }
    println!(
        "median us: warm {:.1}, batched {:.1}, drop {:.1}",
        median(warm),
        median(batched),
        median(drops)
    );
}

fn main() {
    let n: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(10);
    let world = world_at(14.0);
    if std::env::var_os("LFS_CYCLE_TIME").is_some() {
        timings(&world);
        return;
    }
    let mut worlds = vec![world; n];
    // Tables built once per process are already initialised by the flight above.
    cycles(&mut worlds);
    let w = &worlds[0];
    // FNV-1a over the tree, the memory and the vehicle: equal digests mean bit-identical results.
    let mut digest: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |v: u64| digest = (digest ^ v).wrapping_mul(0x0100_0000_01b3);
    for node in w.planner().tree() {
        let p = &node.position_enu;
        [p.x, p.y, p.z, node.total_cost]
            .iter()
            .for_each(|b| eat(u64::from(b.to_bits())));
    }
    for (p, age) in w.planner().memory().points() {
        [p.x, p.y, p.z, age].iter().for_each(|b| eat(u64::from(b.to_bits())));
    }
    w.vehicle.position_enu.iter().for_each(|b| eat(b.to_bits()));
    println!(
        "{n} cycles; memory {} points; tree {} nodes; digest {digest:016x}",
        w.planner().memory().len(),
        w.planner().tree().len(),
    );
    if std::env::var_os("LFS_CYCLE_FLIGHT").is_some() {
        // A whole flight: the trajectory's digest checks many more cycles than the one above.
        let mut w = world_at(0.0);
        while step(&mut w, 0.1).is_none() {}
        let mut digest: u64 = 0xcbf2_9ce4_8422_2325;
        for s in &w.trajectory().samples {
            for b in [s.x, s.y, s.z] {
                digest = (digest ^ b.to_bits()).wrapping_mul(0x0100_0000_01b3);
            }
        }
        println!(
            "flight: {:?} after {} cycles; trajectory digest {digest:016x}",
            w.status, w.cycles
        );
    }
}
