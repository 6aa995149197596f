//! `prgenuav-sim`: the simulator standalone, like jMAVSim, for people who start PX4 themselves.
//!
//! Parses the flags into a library configuration, runs it, and maps the outcome to an exit code in one
//! place: 0 stopped cleanly (Ctrl-C), 1 the link failed, 2 bad input or a resource that could not be had.

use std::net::{SocketAddr, ToSocketAddrs};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::Parser;
use geodesy::GeoPoint;
use nalgebra::Vector3;
use simulator::hil::gateway::GatewayConfig;
use simulator::hil::lockstep::LockstepConfig;
use simulator::hil::serial::WallClockConfig;
use simulator::hil::tcp::port_of_instance;
use simulator::world::wind::WindConfig;
use simulator::{Cancel, SimConfig, SimError, Simulator};

/// prgenuav's vehicle simulator: feeds PX4 an iris quadrotor's sensors over the HIL protocol.
///
/// SITL: start this, then PX4 with PX4_SIM_MODEL=none_iris (v1.14 and later, PX4_SIMULATOR unset) or
/// PX4_SIM_MODEL=iris with -s etc/init.d-posix/rcS (v1.12); PX4 instance N connects to TCP 4560+N.
/// A board (HITL, SYS_HITL 1): --serial /dev/ttyACM0:921600 --gateway udp:127.0.0.1:14550.
#[derive(Debug, Parser)]
#[command(name = "prgenuav-sim", version)]
struct Args {
    /// PX4 instance to serve in lockstep (TCP port 4560 + N).
    #[arg(long, short = 'i', default_value_t = 0)]
    instance: u16,
    /// Home: latitude,longitude,altitude (degrees, degrees, metres above mean sea level).
    #[arg(long, default_value = "47.397742,8.545594,488", value_parser = parse_home)]
    home: GeoPoint,
    /// Seed of every random draw (sensor noise, gusts).
    #[arg(long, short = 's', default_value_t = 0)]
    seed: u64,
    /// Highest real-time factor in lockstep (like PX4_SIM_SPEED_FACTOR); 0 = as fast as PX4 answers.
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Mean wind, the air's velocity north,east in m/s (e.g. 0,3 blows towards the East).
    #[arg(long, value_parser = parse_wind, default_value = "0,0")]
    wind: (f64, f64),
    /// Gusts: standard deviation per axis, m/s (0: steady wind).
    #[arg(long, default_value_t = 0.0)]
    gust: f64,
    /// Longest wait for PX4's answer to a step, milliseconds (then it steps anyway and counts it).
    #[arg(long, default_value_t = 100)]
    actuator_wait_ms: u64,
    /// How long to wait for PX4 to connect, seconds.
    #[arg(long, default_value_t = 600)]
    connect_timeout_s: u64,
    /// A board (or a pty) on the wall clock instead of SITL lockstep: DEVICE:BAUD.
    #[arg(long, value_parser = parse_serial)]
    serial: Option<(String, u32)>,
    /// With --serial: forward the board's other MAVLink traffic to udp:HOST:PORT, and back.
    #[arg(long, value_parser = parse_gateway, requires = "serial")]
    gateway: Option<SocketAddr>,
}

fn parse_home(s: &str) -> Result<GeoPoint, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [lat, lon, alt] = parts[..] else {
        return Err(format!("'{s}' is not LAT,LON,ALT (e.g. 47.397742,8.545594,488)"));
    };
    let num = |x: &str, what: &str| x.parse::<f64>().map_err(|_| format!("{what} '{x}' is not a number"));
    let (lat, lon, alt) = (num(lat, "latitude")?, num(lon, "longitude")?, num(alt, "altitude")?);
    if !(-90.0..=90.0).contains(&lat) || !(-180.0..=180.0).contains(&lon) || !(-500.0..=9000.0).contains(&alt) {
        return Err(format!(
            "'{s}' is out of range: latitude -90..90, longitude -180..180, altitude -500..9000 m"
        ));
    }
    Ok(GeoPoint {
        lat_deg: lat,
        lon_deg: lon,
        alt_m: alt,
    })
}

fn parse_wind(s: &str) -> Result<(f64, f64), String> {
    let (n, e) = s
        .split_once(',')
        .ok_or_else(|| format!("'{s}' is not NORTH,EAST in m/s (e.g. 0,3)"))?;
    let num = |x: &str| x.trim().parse::<f64>().map_err(|_| format!("'{x}' is not a number"));
    Ok((num(n)?, num(e)?))
}

fn parse_serial(s: &str) -> Result<(String, u32), String> {
    let (dev, baud) = s
        .rsplit_once(':')
        .ok_or_else(|| format!("'{s}' is not DEVICE:BAUD (e.g. /dev/ttyACM0:921600)"))?;
    let baud = baud
        .parse::<u32>()
        .map_err(|_| format!("baud '{baud}' is not a number (e.g. 921600)"))?;
    Ok((dev.to_string(), baud))
}

fn parse_gateway(s: &str) -> Result<SocketAddr, String> {
    let rest = s
        .strip_prefix("udp:")
        .ok_or_else(|| format!("'{s}' is not udp:HOST:PORT (e.g. udp:127.0.0.1:14550)"))?;
    rest.to_socket_addrs()
        .map_err(|e| format!("'{rest}' is no address: {e}"))?
        .next()
        .ok_or_else(|| format!("'{rest}' resolves to no address"))
}

fn config(a: &Args) -> SimConfig {
    SimConfig {
        home: a.home,
        seed: a.seed,
        wind: WindConfig {
            mean_ned_m_s: Vector3::new(a.wind.0, a.wind.1, 0.0),
            gust_sigma_m_s: a.gust,
            ..WindConfig::default()
        },
        ..SimConfig::default()
    }
}

#[tokio::main]
async fn main() -> ExitCode {
    let args = Args::parse();
    let mut sim = Simulator::new(config(&args));
    let cancel = Cancel::new();
    let c = cancel.clone();
    tokio::spawn(async move {
        if tokio::signal::ctrl_c().await.is_ok() {
            c.cancel();
        }
    });
    spawn_status(&sim, cancel.clone());
    let outcome = match &args.serial {
        Some((dev, baud)) => run_serial(&mut sim, &args, dev, *baud, &cancel).await,
        None => run_tcp(&mut sim, &args, &cancel).await,
    };
    match outcome {
        Ok(summary) => {
            eprintln!("prgenuav-sim: stopped: {summary}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("prgenuav-sim: {e}");
            let bad_input = matches!(
                e,
                SimError::PortInUse { .. }
                    | SimError::Listen { .. }
                    | SimError::SerialOpen { .. }
                    | SimError::Gateway { .. }
            );
            ExitCode::from(if bad_input { 2 } else { 1 })
        }
    }
}

async fn run_tcp(sim: &mut Simulator, a: &Args, cancel: &Cancel) -> Result<String, SimError> {
    let port = port_of_instance(a.instance);
    let addr = SocketAddr::from(([127, 0, 0, 1], port));
    let lockstep = LockstepConfig {
        actuator_wait: Duration::from_millis(a.actuator_wait_ms.max(1)),
        speed_cap: (a.speed > 0.0).then_some(a.speed),
        freewheel_speed: a.speed.max(1.0),
        ..LockstepConfig::default()
    };
    eprintln!(
        "prgenuav-sim: waiting for PX4 instance {} on TCP {addr} (lockstep)",
        a.instance
    );
    let r = sim
        .serve_sitl(addr, Duration::from_secs(a.connect_timeout_s), &lockstep, cancel)
        .await?;
    Ok(format!(
        "{:.1} s simulated in {:.1} s (x{:.2}), {} steps, {} answers, {} waits timed out",
        r.sim_s,
        r.wall_s,
        r.real_time_factor(),
        r.lockstep.steps,
        r.lockstep.answers,
        r.lockstep.timeouts
    ))
}

async fn run_serial(sim: &mut Simulator, a: &Args, dev: &str, baud: u32, cancel: &Cancel) -> Result<String, SimError> {
    let gateway = a.gateway.map(|remote| GatewayConfig {
        bind: SocketAddr::from(([0, 0, 0, 0], 0)),
        remote,
    });
    eprintln!("prgenuav-sim: board on {dev} at {baud} baud, wall clock 250 Hz");
    let r = sim
        .run_hitl(dev, baud, gateway, &WallClockConfig::default(), cancel)
        .await?;
    Ok(format!(
        "{} steps in {:.1} s, {} late ticks, {} motor commands, gateway {} out / {} in",
        r.steps, r.wall_s, r.late_ticks, r.answers, r.to_endpoint, r.to_board
    ))
}

/// A line to stderr every 10 s of wall time: simulated time and where the vehicle is.
fn spawn_status(sim: &Simulator, cancel: Cancel) {
    let (clock, truth) = (sim.clock(), sim.truth());
    tokio::spawn(async move {
        let t0 = Instant::now();
        loop {
            tokio::select! {
                _ = tokio::time::sleep(Duration::from_secs(10)) => {}
                _ = cancel.cancelled() => return,
            }
            let t = *truth.borrow();
            eprintln!(
                "prgenuav-sim: wall {:.0} s, sim {}, NED ({:.2}, {:.2}, {:.2}) m, {}",
                t0.elapsed().as_secs_f64(),
                clock.now(),
                t.position_ned_m.x,
                t.position_ned_m.y,
                t.position_ned_m.z,
                if t.on_ground { "on ground" } else { "airborne" }
            );
        }
    });
}
