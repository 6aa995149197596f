//! How closely does the mock autopilot (the default high-fidelity side of `generate`) reproduce the recorded
//! competition flights? Flies every recorded case of DIR on an embedded lockstep mock in `avoidance` mode
//! through the bridge, with the companion planning on the pose LATENCY ms old, and compares the flown
//! minimum distance with the real one: the same aggregates as `prgenuav fidelity` (MAE, Spearman, precision
//! and recall of "< 1.5 m"). Used to fit the campaign's default mock latency.
//!
//! `cargo run --release --example mock_fidelity -- [DIR=tests/data/hfs-flights] [LATENCY_MS=0|free] [PARALLEL=2]`
//! (env `TRAJ_DIR=DIR`: keep each flown trajectory as `DIR/<id>.csv`; `VERBOSE=1`: one line per flight; `EXTRA_PARAMS=NAME=V,...`: more vehicle parameters;
//! `MOCK_PROFILE=NAME`: that mock profile instead of the default)

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT;
use mock_autopilot::{LinkSpec, SpeedFactor};
use prgenuav::bridge::{CancelToken, FlyMode, FlyOptions, fly};
use prgenuav::campaign::fly::mock_mavlink::mock_builder_with;
use prgenuav::campaign::settings::mock_profile::MockProfile;
use prgenuav::lfs::fidelity::{FlightCase, aggregate, load_dir};
use prgenuav::model::TestCase;
use tokio::sync::Semaphore;

/// Upper bound of the mock's clock (lockstep holds it back whenever the planner is slower).
const SPEED: f64 = 100.0;

async fn fly_case(case: FlightCase, latency: Option<Duration>) -> anyhow::Result<Option<f64>> {
    // Without lockstep nothing holds the clock back for the planner, so it runs at a moderate 20x.
    let speed = if latency.is_some() { SPEED } else { 20.0 };
    let base = TestCase::load(Path::new(&format!("missions/{}.yaml", case.mission_name)))?;
    let mut test = base.with_obstacles(case.obstacles.clone());
    test.params = case.params.clone();
    // EXTRA_PARAMS=NAME=VALUE,... sets more vehicle parameters (experiments: what would move the mock closer).
    prgenuav::model::Param::override_from_list(&mut test.params, &std::env::var("EXTRA_PARAMS").unwrap_or_default())
        .map_err(|e| anyhow::anyhow!("EXTRA_PARAMS: {e}"))?;
    let profile = match std::env::var("MOCK_PROFILE") {
        Ok(name) => MockProfile::named(&name).map_err(|e| anyhow::anyhow!("MOCK_PROFILE: {e}"))?,
        Err(_) => MockProfile::default(),
    };
    let mock = mock_builder_with(&profile, FlyMode::Avoidance)
        .link(LinkSpec::UdpIn("127.0.0.1:0".parse()?))
        .speed_factor(SpeedFactor::Times(speed))
        .lockstep(latency.map(|_| DEFAULT_LOCKSTEP_WAIT))
        .spawn()
        .await?;
    let port = mock
        .local_addr()
        .map(|a| a.port())
        .ok_or_else(|| anyhow::anyhow!("no port"))?;
    let opts = FlyOptions {
        connect: format!("udpout:127.0.0.1:{port}"),
        mode: FlyMode::Avoidance,
        time_scale: speed,
        lockstep: latency,
        // The recorded flights' definition (the case's offset is subtracted below), as `fidelity` judges.
        judge: prgenuav::judge::Judge::E2025,
        // TRAJ_DIR=DIR keeps each flown trajectory as DIR/<id>.csv, to compare paths with the recorded ones.
        trajectory_csv: std::env::var_os("TRAJ_DIR").map(|d| PathBuf::from(d).join(format!("{}.csv", case.id))),
        ..FlyOptions::default()
    };
    let report = fly(&test, &opts, CancelToken::new()).await;
    let _ = mock.shutdown().await;
    let report = report?;
    if report.min_distance.is_none() || std::env::var_os("VERBOSE").is_some() {
        eprintln!(
            "{}: {:?} {:?} {:?}",
            case.id, report.status, report.reason, report.min_distance
        );
    }
    Ok(report.min_distance.map(|d| (d - case.definition_offset_m).max(0.0)))
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let dir = PathBuf::from(args.next().unwrap_or_else(|| "tests/data/hfs-flights".into()));
    let latency_arg = args.next().unwrap_or_else(|| "0".into());
    let latency_ms: Option<f64> = if latency_arg == "free" {
        None
    } else {
        Some(latency_arg.parse()?)
    };
    let parallel: usize = args.next().map_or(Ok(2), |a| a.parse())?;
    let latency = latency_ms.map(|ms| Duration::from_secs_f64(ms.clamp(0.0, 1000.0) / 1000.0));
    let (cases, _) = load_dir(&dir)?;
    let cases: Vec<FlightCase> = cases.into_iter().filter(|c| !c.obstacles.is_empty()).collect();
    let rt = tokio::runtime::Runtime::new()?;
    let gate = Arc::new(Semaphore::new(parallel.max(1)));
    let rows = rt.block_on(async {
        let mut handles = Vec::new();
        for case in cases {
            let gate = gate.clone();
            handles.push(tokio::spawn(async move {
                let _permit = gate.acquire_owned().await?;
                let real = case.real_m;
                let id = case.id.clone();
                let flown = fly_case(case, latency).await?;
                anyhow::Ok((id, real, flown))
            }));
        }
        let mut rows = Vec::new();
        for h in handles {
            rows.push(h.await??);
        }
        anyhow::Ok(rows)
    })?;
    println!("id,real_m,mock_m");
    for (id, real, flown) in &rows {
        println!("{id},{real:.3},{}", flown.map_or(String::new(), |f| format!("{f:.3}")));
    }
    let pairs: Vec<(f64, f64)> = rows.iter().filter_map(|(_, r, f)| Some(((*f)?, *r))).collect();
    let a = aggregate(&pairs);
    eprintln!(
        "latency {latency_arg} ms: n {} MAE {:?} Spearman {:?} precision {:?} recall {:?}",
        a.n, a.mae, a.spearman, a.precision, a.recall
    );
    Ok(())
}
