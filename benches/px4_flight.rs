//! Wall time of one mission-2 avoidance flight on real PX4 SITL, side by side in one run: PX4's SIH at speed
//! factor 5 (on the wall clock), and prgenuav's iris simulator in lockstep capped at 5 and uncapped. Each
//! sample is a fresh PX4 (and simulator) booted, flown and stopped, as a campaign flies it.
//!
//! `PX4_SITL_BIN=/path/to/build/px4_sitl_default/bin/px4 cargo bench --bench px4_flight`; without the
//! variable it says so and measures nothing.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use prgenuav::bridge::hil::sitl::{IrisSitl, IrisSpec};
use prgenuav::bridge::sitl::{Px4Build, Px4Sitl, SitlSpec};
use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, SimLink, Status, fly};
use prgenuav::generator::{Generator, GeneratorConfig};
use prgenuav::model::TestCase;

/// The speed factor SIH flies at in campaigns, and the iris's lockstep cap beside it.
const SPEED: f64 = 5.0;
/// The iris uncapped: lockstep then runs as fast as PX4 and the companion answer.
const UNCAPPED: f64 = 1000.0;

fn mission_2() -> TestCase {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
    let case = TestCase::load(&path).expect("mission 2");
    let g = Generator::new(&case, GeneratorConfig::default(), 1).expect("generator");
    case.with_obstacles(g.sample(0).expect("sample").obstacles.to_vec())
}

fn options(url: String, speed: f64) -> FlyOptions {
    FlyOptions {
        connect: url,
        mode: FlyMode::Avoidance,
        time_scale: speed,
        timeout_s: 400.0,
        heartbeat_wait_s: 60.0,
        // As `fly --px4` does: the bridge times by the vehicle's measured clock (uncapped, the machine's pace).
        detect_time_scale: true,
        ..FlyOptions::default()
    }
}

fn landed(rt: &tokio::runtime::Runtime, test: &TestCase, opts: &FlyOptions) {
    let r = rt
        .block_on(fly(test, opts, CancelToken::new()))
        .expect("the flight runs");
    assert_eq!(r.status, Status::Landed, "{:?}", r.reason);
}

fn sih_flight(rt: &tokio::runtime::Runtime, build: &Px4Build, test: &TestCase) -> Duration {
    let t0 = Instant::now();
    let px4 = Px4Sitl::start(&SitlSpec::for_build(build, 0, SPEED).at(test.home)).expect("PX4 SIH starts");
    landed(rt, test, &options(px4.url(), SPEED));
    drop(px4);
    t0.elapsed()
}

fn iris_flight(rt: &tokio::runtime::Runtime, build: &Px4Build, test: &TestCase, speed: f64) -> Duration {
    let t0 = Instant::now();
    let spec = IrisSpec {
        build: build.clone(),
        instance: 0,
        home: test.home,
        heading_deg: 0.0,
        seed: 0,
        speed_factor: speed,
        link: SimLink::Tcp,
        paced: true,
        boot_timeout: Duration::from_secs(60),
    };
    let mut pair = IrisSitl::start(rt.handle(), &spec, &AtomicBool::new(false)).expect("PX4 and the iris start");
    let mut opts = options(pair.px4.url(), speed);
    opts.sim_gate = pair.gate();
    opts.lockstep = Some(Duration::ZERO);
    landed(rt, test, &opts);
    pair.finish();
    drop(pair);
    t0.elapsed()
}

fn flights(c: &mut Criterion) {
    let Some(bin) = std::env::var_os("PX4_SITL_BIN").filter(|b| !b.is_empty()) else {
        eprintln!("px4_flight: set PX4_SITL_BIN=/path/to/build/px4_sitl_default/bin/px4 (a PX4 SITL you built)");
        return;
    };
    let root = PathBuf::from(bin)
        .parent()
        .and_then(Path::parent)
        .map(Path::to_path_buf);
    let build = Px4Build::open(&root.expect("BUILD/bin/px4")).expect("a PX4 SITL build");
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    let test = mission_2();
    let mut g = c.benchmark_group("px4_mission_2_flight");
    // Flat: one flight per sample (a linear sampling would fly 55 per variant).
    g.sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(1));
    g.measurement_time(Duration::from_secs(200));
    g.bench_function("sih_x5", |b| {
        b.iter_custom(|n| (0..n).map(|_| sih_flight(&rt, &build, &test)).sum())
    });
    g.bench_function("iris_lockstep_cap_x5", |b| {
        b.iter_custom(|n| (0..n).map(|_| iris_flight(&rt, &build, &test, SPEED)).sum())
    });
    g.bench_function("iris_lockstep_uncapped", |b| {
        b.iter_custom(|n| (0..n).map(|_| iris_flight(&rt, &build, &test, UNCAPPED)).sum())
    });
    g.finish();
}

criterion_group!(benches, flights);
criterion_main!(benches);
