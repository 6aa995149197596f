//! Real PX4 as a second reference: flies every recorded case of DIR (the competition's own flights) on a fresh
//! PX4 SITL instance (SIH quadrotor, the competition's home, speed factor 5) with our companion in `avoidance`
//! mode, and appends one row per flight to OUT/flights.csv: the recorded minimum distance, PX4's, status, times and the companion's answer latency. Each
//! flown trajectory is kept as OUT/traj/<id>.csv (Aerialist columns, 0.5 s bins, the test's frame).
//!
//! Resumable: cases already in OUT/flights.csv are skipped, so an interrupted run goes on where it stopped.
//! Distances are in the case's own definition (a tier-B case subtracts half the vehicle width), as `fidelity`
//! compares them.
//!
//! `PX4_SITL_BIN=BUILD/bin/px4 cargo run --release --example px4_reference -- [DIR=tests/data/hfs-flights]
//! [OUT=tests/data/px4-flights] [INSTANCES=1]` (env `ONLY=id,id`: just those cases; `TIER=A`: just that tier;
//! `EXTRA_PARAMS=NAME=V,...`: more vehicle parameters; `NO_FENCE=1`: no geofence; `PLAN_AGE=1`, `YAW_RATE=0`: companion styles, see `companion_style`; `CONSOLE=1`: PX4's console of a refused flight; `FIRST_INSTANCE=K`: PX4 instances from K; `HEADING=DEG`, `SPEED=F`: see below; `SIM=iris`: PX4 in external-simulator mode fed by
//! prgenuav's iris simulator in lockstep, the companion on simulated time, at the case's home; any release
//! from v1.12, which has no SIH)

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::Context;
use prgenuav::bridge::companion::planner_steer::{CompanionStyle, PlanAge, YawRateField};
use prgenuav::bridge::hil::sitl::{IrisSitl, IrisSpec};
use prgenuav::bridge::sitl::{Px4Build, Px4Sitl, SitlSpec};
use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, SimLink, fly};
use prgenuav::lfs::fidelity::{FlightCase, load_dir};
use prgenuav::model::TestCase;

/// PX4_SIM_SPEED_FACTOR (env `SPEED`: another; with `SIM=iris` the lockstep's cap, 1000 = uncapped).
fn speed() -> f64 {
    std::env::var("SPEED").ok().and_then(|s| s.parse().ok()).unwrap_or(5.0)
}

/// `HEADING=DEG`: the iris's nose at rest, clockwise from North (Gazebo Classic spawns it East, 90).
fn heading_deg() -> anyhow::Result<f64> {
    match std::env::var("HEADING") {
        Ok(s) => s.parse().map_err(|_| anyhow::anyhow!("HEADING={s:?} is not degrees")),
        Err(_) => Ok(0.0),
    }
}
/// `PLAN_AGE=1`: the companion's waypoint generator follows the previous step's path; `YAW_RATE=0`: its answers
/// carry a yaw rate of 0 (PX4-Avoidance's, as read) instead of NaN.
fn companion_style() -> CompanionStyle {
    let on = |name: &str, value: &str| std::env::var(name).as_deref() == Ok(value);
    CompanionStyle {
        plan_age: if on("PLAN_AGE", "1") {
            PlanAge::OnePeriod
        } else {
            PlanAge::Fresh
        },
        yaw_rate: if on("YAW_RATE", "0") {
            YawRateField::Zero
        } else {
            YawRateField::Unset
        },
    }
}

/// Vehicle seconds before the bridge lands the vehicle (the competition's limit is 300 s of wall time at x1).
const TIMEOUT_S: f64 = 400.0;
const HEADER: &str = "id,tier,mission,real_m,px4_m,status,reason,flight_time_s,wall_s,answer_p99_ms,clock_rate";

fn test_of(case: &FlightCase) -> anyhow::Result<TestCase> {
    let base = TestCase::load(Path::new(&format!("missions/{}.yaml", case.mission_name)))?;
    let mut test = base.with_obstacles(case.obstacles.clone());
    test.params = case.params.clone();
    // EXTRA_PARAMS=NAME=VALUE,...: more vehicle parameters (experiments on what moves PX4 towards the recorded flights).
    prgenuav::model::Param::override_from_list(&mut test.params, &std::env::var("EXTRA_PARAMS").unwrap_or_default())
        .map_err(|e| anyhow::anyhow!("EXTRA_PARAMS: {e}"))?;
    Ok(test)
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// PX4 flying one case: SIH, or PX4 and prgenuav's iris simulator (`SIM=iris`), stopped when dropped.
enum Vehicle {
    Sih(Px4Sitl),
    Iris(IrisSitl),
}

impl Vehicle {
    fn start(bin: &Path, instance: u8, test: &TestCase) -> anyhow::Result<Vehicle> {
        if std::env::var("SIM").as_deref() != Ok("iris") {
            return Ok(Vehicle::Sih(Px4Sitl::start(&SitlSpec::new(bin, instance, speed()))?));
        }
        let root = bin
            .parent()
            .and_then(Path::parent)
            .context("PX4_SITL_BIN is BUILD/bin/px4")?;
        let spec = IrisSpec {
            build: Px4Build::open(root)?,
            instance,
            home: test.home,
            heading_deg: heading_deg()?,
            seed: 0,
            speed_factor: speed(),
            link: SimLink::Tcp,
            paced: true,
            boot_timeout: Duration::from_secs(60),
        };
        let pair = IrisSitl::start(&tokio::runtime::Handle::current(), &spec, &AtomicBool::new(false))?;
        Ok(Vehicle::Iris(pair))
    }

    fn options(&self) -> FlyOptions {
        match self {
            Vehicle::Sih(px4) => FlyOptions {
                connect: px4.url(),
                ..FlyOptions::default()
            },
            Vehicle::Iris(pair) => FlyOptions {
                connect: pair.px4.url(),
                sim_gate: pair.gate(),
                lockstep: Some(Duration::ZERO),
                // Uncapped (`SPEED=1000`), the lockstep runs at the machine's pace: time by the measured clock.
                detect_time_scale: true,
                ..FlyOptions::default()
            },
        }
    }
}

async fn fly_case(case: &FlightCase, bin: &Path, instance: u8, out: &Path) -> anyhow::Result<String> {
    let test = test_of(case)?;
    let vehicle = tokio::task::block_in_place(|| Vehicle::start(bin, instance, &test))?;
    let opts = FlyOptions {
        mode: FlyMode::Avoidance,
        time_scale: speed(),
        timeout_s: TIMEOUT_S,
        heartbeat_wait_s: 60.0,
        // The recorded flights' definition (fidelity compares like for like).
        judge: prgenuav::judge::Judge::E2025,
        // NO_FENCE=1: the boxes are not uploaded as geofence exclusions (what PX4's mission check reads).
        fence: std::env::var("NO_FENCE").is_err(),
        companion: companion_style(),
        ..vehicle.options()
    };
    let wall = Instant::now();
    let r = tokio::time::timeout(Duration::from_secs(600), fly(&test, &opts, CancelToken::new()))
        .await
        .context("flight within 10 min of wall time")??;
    let wall_s = wall.elapsed().as_secs_f64();
    if r.status == prgenuav::bridge::Status::Rejected && std::env::var_os("CONSOLE").is_some() {
        // CONSOLE=1: why PX4 refused, in its own words.
        let px4 = match &vehicle {
            Vehicle::Sih(px4) => px4,
            Vehicle::Iris(pair) => &pair.px4,
        };
        eprintln!("{}: PX4 console:\n{}", case.id, px4.console_tail(80).join("\n"));
    }
    tokio::task::block_in_place(|| drop(vehicle));
    let traj = r.trajectory.binned(0.5);
    let tmp = out.join("traj").join(format!("{}.csv.tmp", case.id));
    std::fs::write(&tmp, traj.to_csv())?;
    std::fs::rename(&tmp, out.join("traj").join(format!("{}.csv", case.id)))?;
    let adjust = |d: Option<f64>| {
        d.map_or(String::new(), |d| {
            format!("{:.3}", (d - case.definition_offset_m).max(0.0))
        })
    };
    Ok(format!(
        "{},{},{},{:.3},{},{},{},{:.1},{:.1},{},{}",
        case.id,
        case.tier,
        case.mission_name,
        case.real_m,
        adjust(r.min_distance),
        r.status.as_str(),
        csv_field(r.reason.as_deref().unwrap_or("")),
        r.flight_time_s,
        wall_s,
        r.companion_timing
            .map_or(String::new(), |t| format!("{:.1}", t.request_to_answer_ms.p99)),
        r.clock
            .and_then(|c| c.measured_rate)
            .map_or(String::new(), |c| format!("{c:.2}")),
    ))
}

fn main() -> anyhow::Result<()> {
    let bin = PathBuf::from(
        std::env::var_os("PX4_SITL_BIN").context("set PX4_SITL_BIN=BUILD/bin/px4 (a PX4 v1.14 SITL you built)")?,
    );
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().unwrap_or_else(|| "tests/data/hfs-flights".into()));
    let out = PathBuf::from(args.next().unwrap_or_else(|| "tests/data/px4-flights".into()));
    let instances: u8 = args.next().map_or(Ok(1), |a| a.parse())?;
    std::fs::create_dir_all(out.join("traj"))?;
    let table = out.join("flights.csv");
    let done: Vec<String> = std::fs::read_to_string(&table)
        .unwrap_or_default()
        .lines()
        .skip(1)
        .filter_map(|l| l.split(',').next().map(str::to_string))
        .collect();
    if done.is_empty() {
        std::fs::write(&table, format!("{HEADER}\n"))?;
    }
    let only: Option<Vec<String>> = std::env::var("ONLY")
        .ok()
        .map(|s| s.split(',').map(str::to_string).collect());
    let (cases, _) = load_dir(&dir)?;
    let todo: Vec<FlightCase> = cases
        .into_iter()
        .filter(|c| !c.obstacles.is_empty() && !done.contains(&c.id))
        .filter(|c| only.as_ref().is_none_or(|o| o.contains(&c.id)))
        .filter(|c| std::env::var("TIER").map_or(true, |t| t == c.tier))
        .collect();
    eprintln!(
        "{} cases to fly ({} already in {})",
        todo.len(),
        done.len(),
        table.display()
    );
    let queue = Arc::new(Mutex::new(todo));
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    rt.block_on(async {
        let mut workers = Vec::new();
        // FIRST_INSTANCE=K: PX4 instances K.. (v1.12.3 with the iris refuses avoidance flights on instance 0).
        let first: u8 = std::env::var("FIRST_INSTANCE")
            .ok()
            .and_then(|k| k.parse().ok())
            .unwrap_or(0);
        let last = u32::from(first) + u32::from(instances.max(1)) - 1;
        if last >= u32::from(prgenuav::bridge::sitl::slot::SLOTS) {
            // PX4 sends instance 10 and up's API link to 14549, not 14540 + i (px4-rc.mavlink): no heartbeat.
            anyhow::bail!(
                "FIRST_INSTANCE={first} with INSTANCES={instances} reaches instance {last}: PX4 instances 0-{} only",
                prgenuav::bridge::sitl::slot::SLOTS - 1
            );
        }
        for instance in (0..instances.max(1)).map(|i| i.saturating_add(first)) {
            let (queue, bin, out, table) = (queue.clone(), bin.clone(), out.clone(), table.clone());
            workers.push(tokio::spawn(async move {
                loop {
                    let next = queue.lock().map_err(|_| anyhow::anyhow!("queue poisoned"))?.pop();
                    let Some(case) = next else { break };
                    match fly_case(&case, &bin, instance, &out).await {
                        Ok(row) => {
                            eprintln!("{row}");
                            let mut f = std::fs::OpenOptions::new().append(true).open(&table)?;
                            writeln!(f, "{row}")?;
                        }
                        // Not recorded: a resumed run tries it again.
                        Err(e) => eprintln!("{}: not flown: {e:#}", case.id),
                    }
                }
                anyhow::Ok(())
            }));
        }
        for w in workers {
            w.await??;
        }
        anyhow::Ok(())
    })
}
