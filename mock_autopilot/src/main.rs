//! `mock-autopilot`: run the PX4-like mock vehicle on a MAVLink link until Ctrl-C.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use clap::Parser;
use mavlink::dialects::common::MavMissionResult;
use mock_autopilot::obstacles::ObstacleWorld;
use mock_autopilot::release::Px4Release;
use mock_autopilot::{Faults, LinkSpec, MockAutopilot, SpeedFactor};

/// A PX4-like MAVLink vehicle (quadrotor, sysid 1) for tests without hardware.
#[derive(Debug, Parser)]
#[command(name = "mock-autopilot", version)]
struct Args {
    /// PX4 SITL instance N: bind 127.0.0.1:14580+N, send to 127.0.0.1:14540+N.
    #[arg(long, default_value_t = 0)]
    instance: u16,
    /// Any rust-mavlink address instead (udpin:HOST:PORT, udpout:HOST:PORT, tcpin:..., serial:DEV:BAUD).
    #[arg(long)]
    link: Option<String>,
    /// Simulated time runs K times faster than wall time ("max": unpaced).
    #[arg(long, default_value = "1", value_parser = SpeedFactor::parse)]
    speed_factor: SpeedFactor,
    /// Lockstep with the avoidance companion: with COM_OBS_AVOID = 1, simulated time stands still after
    /// each trajectory request until the companion answers (at most --lockstep-wait wall seconds).
    /// --speed-factor becomes an upper bound. For fault-free links.
    #[arg(long)]
    lockstep: bool,
    /// Wall-time bound of one lockstep wait, seconds.
    #[arg(long, default_value_t = 2.0, requires = "lockstep")]
    lockstep_wait: f64,
    /// Fixed physics step, milliseconds.
    #[arg(long, default_value_t = 4.0)]
    step_ms: f64,
    /// Seed of every random choice: link faults and gusts.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Seeded horizontal gusts, RMS per axis in m/s² (0: none): a flight-to-flight scatter like real PX4
    /// SITL's, each arming drawing new gusts from --seed.
    #[arg(long, default_value_t = 0.0)]
    gust_acc: f64,
    /// Correlation time of the gusts, seconds.
    #[arg(long, default_value_t = 1.0)]
    gust_tau: f64,
    /// Probability of dropping each message (both directions).
    #[arg(long, default_value_t = 0.0)]
    loss: f64,
    /// Probability of duplicating each message (both directions).
    #[arg(long, default_value_t = 0.0)]
    duplicate: f64,
    /// One-way latency in simulated milliseconds.
    #[arg(long, default_value_t = 0.0)]
    latency: f64,
    /// Answer every mission upload with this MAV_MISSION_RESULT code (1..=15).
    #[arg(long)]
    reject_mission: Option<u32>,
    /// Refuse every arming attempt.
    #[arg(long)]
    fail_arm: bool,
    /// Simulated seconds after boot until the estimator has converged (arming refused, no GPS fix or home
    /// before), as PX4 SITL after start.
    #[arg(long, default_value_t = mock_autopilot::preflight::DEFAULT_ESTIMATOR_SETTLE.as_secs_f64())]
    estimator_settle: f64,
    /// Reboot once after S simulated seconds.
    #[arg(long)]
    reboot_after: Option<f64>,
    /// Stop talking and listening after S simulated seconds.
    #[arg(long)]
    silence_after: Option<f64>,
    /// Test case YAML whose obstacles the vehicle can hit.
    #[arg(long)]
    obstacles: Option<PathBuf>,
    /// Entering an obstacle is a crash (disarm, STATUSTEXT, on ground). Needs --obstacles.
    #[arg(long, requires = "obstacles")]
    crash_on_collision: bool,
    /// Boot here (home and EKF origin): LAT,LON,ALT (degrees, degrees, metres AMSL); default PX4 SITL's.
    #[arg(long, value_parser = parse_home, allow_hyphen_values = true)]
    home: Option<geodesy::GeoPoint>,
    /// Act as this PX4 release MAJOR.MINOR.PATCH: what AUTOPILOT_VERSION reports; from 1.16 there is no
    /// COM_OBS_AVOID (no avoidance interface).
    #[arg(long, default_value = "1.14.0", value_parser = Px4Release::parse)]
    px4_version: Px4Release,
}

fn parse_home(s: &str) -> Result<geodesy::GeoPoint, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("{x:?}: {e}")))
        .collect::<Result<_, _>>()?;
    match v[..] {
        [lat_deg, lon_deg, alt_m]
            if (-90.0..=90.0).contains(&lat_deg) && (-180.0..=180.0).contains(&lon_deg) && alt_m.is_finite() =>
        {
            Ok(geodesy::GeoPoint {
                lat_deg,
                lon_deg,
                alt_m,
            })
        }
        _ => Err("expected LAT,LON,ALT with latitude in -90..90 and longitude in -180..180".into()),
    }
}

/// The one checked conversion of a flag's seconds to a [`Duration`]: `v` within `0..=max`.
fn secs(name: &str, v: f64, max: f64) -> Result<Duration> {
    if !(v.is_finite() && (0.0..=max).contains(&v)) {
        bail!("--{name} {v}: expected 0 to {max} seconds");
    }
    Duration::try_from_secs_f64(v).with_context(|| format!("--{name} {v}"))
}

/// The highest `--instance`: its ports 14580+N and 14540+N must exist.
const MAX_INSTANCE: u16 = u16::MAX - 14580;

/// A probability flag within 0..=1.
fn probability(name: &str, p: f64) -> Result<f64> {
    if !(0.0..=1.0).contains(&p) {
        bail!("--{name} {p}: expected a probability from 0 to 1");
    }
    Ok(p)
}

fn link_spec(args: &Args) -> Result<LinkSpec> {
    let Some(link) = &args.link else {
        if args.instance > MAX_INSTANCE {
            bail!(
                "--instance {}: expected 0 to {MAX_INSTANCE} (it binds port 14580+N, and ports end at 65535)",
                args.instance
            );
        }
        return Ok(LinkSpec::Px4Sitl {
            instance: args.instance,
        });
    };
    // Our own UDP handling gives port discovery (port 0) and PX4's reply-to-sender behaviour.
    if let Some(a) = link.strip_prefix("udpin:") {
        let addr: SocketAddr = a.parse().with_context(|| format!("--link {link:?}: bad address"))?;
        return Ok(LinkSpec::UdpIn(addr));
    }
    if let Some(a) = link.strip_prefix("udpout:") {
        let remote: SocketAddr = a.parse().with_context(|| format!("--link {link:?}: bad address"))?;
        let bind = if remote.is_ipv4() { "0.0.0.0:0" } else { "[::]:0" };
        return Ok(LinkSpec::UdpOut {
            bind: bind.parse()?,
            remote,
        });
    }
    Ok(LinkSpec::Address(link.clone()))
}

async fn run(args: Args) -> Result<()> {
    let reject = match args.reject_mission {
        None => None,
        Some(c) => match <MavMissionResult as num_traits::FromPrimitive>::from_u32(c) {
            Some(r) if c != 0 => Some(r),
            _ => bail!("--reject-mission {c}: expected a MAV_MISSION_RESULT error code 1..=15"),
        },
    };
    let faults = Faults {
        seed: args.seed,
        loss: probability("loss", args.loss)?,
        duplicate: probability("duplicate", args.duplicate)?,
        latency: secs("latency", args.latency / 1000.0, 10.0).context("--latency is in milliseconds: 0 to 10000")?,
        silence_after: args
            .silence_after
            .map(|v| secs("silence-after", v, 86_400.0))
            .transpose()?,
        reboot_after: args
            .reboot_after
            .map(|v| secs("reboot-after", v, 86_400.0))
            .transpose()?,
    };
    if !(args.step_ms.is_finite() && args.step_ms > 0.0 && args.step_ms <= 100.0) {
        bail!("--step-ms {}: expected 0 < step <= 100", args.step_ms);
    }
    if !(args.gust_acc.is_finite() && (0.0..=5.0).contains(&args.gust_acc)) {
        bail!("--gust-acc {}: expected 0 to 5 m/s²", args.gust_acc);
    }
    if !(args.gust_tau.is_finite() && (0.05..=60.0).contains(&args.gust_tau)) {
        bail!("--gust-tau {}: expected 0.05 to 60 seconds", args.gust_tau);
    }
    let tuning = mock_autopilot::dynamics::Tuning {
        gust_acc_m_s2: args.gust_acc,
        gust_tau_s: args.gust_tau,
        ..Default::default()
    };
    let mut builder = MockAutopilot::builder()
        .seed(args.seed)
        .tuning(tuning)
        .link(link_spec(&args)?)
        .speed_factor(args.speed_factor)
        .step(Duration::from_secs_f64(args.step_ms / 1000.0))
        .faults(faults)
        .reject_mission(reject)
        .fail_arm(args.fail_arm)
        .px4_release(args.px4_version)
        .estimator_settle(secs("estimator-settle", args.estimator_settle, 600.0)?)
        .lockstep(
            args.lockstep
                .then(|| secs("lockstep-wait", args.lockstep_wait, 60.0))
                .transpose()?,
        );
    if let Some(home) = args.home {
        builder = builder.home(home);
    }
    if let (Some(path), true) = (&args.obstacles, args.crash_on_collision) {
        let world = ObstacleWorld::from_test_file(path).map_err(|e| anyhow::anyhow!("--obstacles: {e}"))?;
        eprintln!("mock-autopilot: {} obstacles loaded", world.len());
        builder = builder.collision(Box::new(world));
    } else if let Some(path) = &args.obstacles {
        // Validate the file even when collisions are off, so typos surface early.
        ObstacleWorld::from_test_file(path).map_err(|e| anyhow::anyhow!("--obstacles: {e}"))?;
    }
    let mock = builder.spawn().await?;
    match mock.local_addr() {
        Some(a) => println!("mock-autopilot listening on {a}"),
        None => println!("mock-autopilot connected on {}", args.link.as_deref().unwrap_or("?")),
    }
    tokio::signal::ctrl_c().await.context("waiting for Ctrl-C")?;
    mock.shutdown().await?;
    Ok(())
}

#[tokio::main]
async fn main() -> ExitCode {
    let args = Args::parse();
    match run(args).await {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("mock-autopilot: {}", message(&e));
            ExitCode::from(2)
        }
    }
}

/// The error and its causes, each once: an error that quotes its cause is not followed by it again.
fn message(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}
