//! `prgenuav fly TEST.yaml [--connect URL | --px4 BUILD_DIR [--sim sih|iris] | --hitl serial:DEV:BAUD]
//! [--mode avoidance|offboard|mission] [--timeout S] [--json] [--trajectory out.csv] [--plot out.svg]
//! [--world out.world] [--no-fence] [--judge 2025|2026] [--anchor-at-vehicle-home] [--strict]`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use prgenuav::bridge::companion::predict::predict_cp;
use prgenuav::bridge::hil::board::BoardPort;
use prgenuav::bridge::hil::run::SimSummary;
use prgenuav::bridge::session::gazebo::world_sdf;
use prgenuav::bridge::wire::notices::NoticeSink;
use prgenuav::bridge::{
    CancelToken, DEFAULT_URL, FlightReport, FlyMode, FlyOptions, LinkAddress, Prediction, Status, fly, predict,
};
use prgenuav::io::write_atomic;
use prgenuav::model::TestCase;
use prgenuav::plot::{FlightPlot, PathStyle};

use super::fly_backend::{Simulated, Started, open_build, start_board, start_px4};
use super::limits;
use super::setting_flags::FlyFlags;
use super::stop_signals::StopSignals;
use prgenuav::campaign::settings::Loaded;
use prgenuav::judge::Judge;
use prgenuav::lfs::sim::Motion;

/// The motion model of `fly`'s low-fidelity prediction: the campaign's screening default, so a flown test is
/// compared with what chose it (`simulate` defaults to the paper's model; `--motion px4` gives this one).
const PREDICTION_MOTION: Motion = Motion::Px4;

/// Arguments of `fly`.
#[derive(Debug, clap::Args)]
pub struct FlyArgs {
    /// The test YAML (mission, parameters, commands and the virtual obstacles).
    test: PathBuf,
    /// The vehicle: udpin:HOST:PORT, udpout:, tcpout:HOST:PORT, serial:/dev/ttyACM0:57600 (or udpin://...).
    #[arg(long, value_name = "URL", default_value = DEFAULT_URL)]
    connect: String,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
    /// Append the flown trajectory to this Aerialist CSV as it arrives.
    #[arg(long, value_name = "FILE.csv")]
    trajectory: Option<PathBuf>,
    /// Write a top-down SVG of the flown and the predicted paths.
    #[arg(long, value_name = "FILE.svg")]
    plot: Option<PathBuf>,
    /// Write the obstacles as a Gazebo Classic world (before flying).
    #[arg(long, value_name = "FILE.world")]
    world: Option<PathBuf>,
    /// Only write the `--world` file, do not fly (to start Gazebo with it first).
    #[arg(long, requires = "world")]
    world_only: bool,
    /// Do not upload the obstacles as a geofence.
    #[arg(long)]
    no_fence: bool,
    /// The vehicle's simulated time runs this many times faster (PX4_SIM_SPEED_FACTOR, mock --speed-factor)
    /// [default: 1; with --px4, the instance's speed factor, 5].
    #[arg(long, value_name = "K")]
    time_scale: Option<f64>,
    /// Skip the low-fidelity prediction.
    #[arg(long)]
    no_predict: bool,
    /// The vehicle is a `mock-autopilot --lockstep`: answer each avoidance request at once, planned on the
    /// pose this many milliseconds old (--time-scale is then the mock's upper bound).
    #[arg(long, value_name = "LATENCY_MS")]
    lockstep: Option<f64>,
    /// Refuse a test that breaks the current competition rules (default: warn and fly it anyway, as the
    /// recorded flights of older editions need).
    #[arg(long)]
    strict: bool,
    /// Wait at most this many (vehicle) seconds for the vehicle to become ready to arm: estimator converged,
    /// GPS fix, home, PX4's pre-arm checks.
    #[arg(long, default_value_t = 60.0, value_name = "S")]
    ready_timeout: f64,
    /// Do not show the vehicle's messages, readiness and clock warnings on stderr as they arrive.
    #[arg(long)]
    quiet: bool,
    /// The flight's settings: its mode, judge, timeout, anchoring and a PX4 started for it.
    #[command(flatten)]
    settings: FlyFlags,
}

/// The settings of one flight, as the flags give them (their defaults from their declarations).
struct Flight {
    mode: FlyMode,
    judge: Judge,
    timeout_s: f64,
    anchor_at_vehicle_home: bool,
    /// `--px4 BUILD_DIR`: a fresh instance started for the flight.
    px4: Option<PathBuf>,
    /// The speed factor of that instance when `--time-scale` does not say.
    px4_speed_factor: f64,
    /// What simulates that instance.
    simulated: Simulated,
    /// `--hitl serial:DEVICE:BAUD`: a board fed by prgenuav's simulator.
    board: Option<BoardPort>,
}

impl Flight {
    fn of(args: &FlyArgs) -> anyhow::Result<Self> {
        let request = args.settings.request(&Loaded::default())?;
        request.check().map_err(anyhow::Error::msg)?;
        let a = request.asked;
        Ok(Self {
            mode: a.campaign.mode(),
            judge: a.campaign.judge(),
            timeout_s: a.flight.timeout_s(),
            anchor_at_vehicle_home: a.flight.anchor_at_vehicle_home(),
            px4: a.vehicles.px4.clone(),
            px4_speed_factor: a.vehicles.speed_factor(),
            simulated: Simulated {
                sim: a.vehicles.sim.unwrap_or_else(|| a.vehicles.bench().sim()),
                link: a.vehicles.sim_link(),
                seed: a.campaign.seed(),
                bench: a.vehicles.bench(),
            },
            board: match a.vehicles.hitl.as_deref() {
                None => None,
                Some([one]) => Some(BoardPort::parse(one).map_err(anyhow::Error::msg)?),
                Some(_) => anyhow::bail!("fly --hitl takes one board (generate --hitl takes several)"),
            },
        })
    }
}

pub fn run(args: FlyArgs) -> anyhow::Result<ExitCode> {
    // Arguments first, resources second.
    let flight = Flight::of(&args)?;
    LinkAddress::parse(&args.connect)?;
    if flight.board.is_some() && args.connect != DEFAULT_URL {
        anyhow::bail!("--hitl flies the board through prgenuav's simulator: give --hitl or --connect, not both");
    }
    super::check_outputs(&[
        ("--plot", args.plot.as_deref()),
        ("--trajectory", args.trajectory.as_deref()),
        ("--world", args.world.as_deref()),
    ])?;
    let build = flight
        .px4
        .as_deref()
        .map(|dir| open_build(dir, flight.mode, &flight.simulated))
        .transpose()?;
    let Some(test) = flown_test(&args, &flight, build.is_some())? else {
        return Ok(ExitCode::from(super::EXIT_FAIL));
    };
    if write_world(&args, &test)? && args.world_only {
        return Ok(ExitCode::SUCCESS);
    }
    let prediction = prediction(&args, &flight, &test);
    let mut opts = options(&args, &flight, prediction.as_ref())?;
    let runtime = tokio::runtime::Runtime::new().context("starting the async runtime")?;
    let quiet = args.json || args.quiet;
    // Started on the main thread, which outlives the flight: PX4 dies with the thread that started it.
    let started = match (&build, &flight.board) {
        (Some(b), _) => start_px4(&runtime, b, &flight.simulated, &test, &mut opts, quiet)?,
        (None, Some(port)) => start_board(&runtime, port, flight.simulated.seed, &test, &mut opts, quiet)?,
        (None, None) => Started::Nothing,
    };
    // Ctrl-C, a scheduler's SIGTERM (`scancel`, a Kubernetes Job's end) and SIGHUP all land the vehicle.
    let mut signals = StopSignals::register(runtime.handle()).context("handling Ctrl-C, SIGTERM and SIGHUP")?;
    let mut report = runtime.block_on(async {
        let cancel = CancelToken::new();
        let on_stop = cancel.clone();
        tokio::spawn(async move {
            let which = signals.next().await;
            eprintln!("{which}: landing the vehicle, keeping the recording");
            on_stop.cancel();
        });
        if !args.json && !args.quiet {
            eprintln!("waiting for a vehicle on {} ...", opts.connect);
        }
        fly(&test, &opts, cancel).await
    })?;
    if build.is_some() {
        report.warnings.extend(flight.simulated.bench.caveats(&test));
    }
    print_console_tail(&started, &report);
    let simulator = started.finish(&runtime);
    if let Some(path) = &args.plot {
        write_plot(path, &test, prediction.as_ref(), &report, opts.mode)?;
    }
    print_anchoring(&report);
    print_report(&report, prediction.is_some(), args.json, simulator.as_ref())?;
    Ok(exit_code(&report))
}

/// PX4's last console lines, for a flight that did not end.
fn print_console_tail(started: &Started, report: &FlightReport) {
    if let Some(tail) = started.console_tail(20).filter(|_| !report.status.completed()) {
        eprintln!("PX4's console, last 20 lines:");
        tail.iter().for_each(|l| eprintln!("  {l}"));
    }
}

/// The test as flown: the bench's parameters over the test's on a PX4 instance started here.
fn flown_test(args: &FlyArgs, flight: &Flight, px4: bool) -> anyhow::Result<Option<TestCase>> {
    let test = super::load_test(&args.test, args.strict)?;
    Ok(test.map(|t| if px4 { flight.simulated.bench.flown(&t) } else { t }))
}

/// The LFS prediction for the mode flown (none with `--no-predict`; a failure is a warning).
fn prediction(args: &FlyArgs, flight: &Flight, test: &TestCase) -> Option<Prediction> {
    (!args.no_predict)
        .then(|| match flight.mode {
            FlyMode::CollisionPrevention => predict_cp(test, flight.judge),
            _ => predict(test, PREDICTION_MOTION.model(), flight.judge),
        })
        .and_then(|p| p.inspect_err(|e| eprintln!("warning: no LFS prediction: {e}")).ok())
}

/// `--json`: the report with the prediction's motion model and what the simulator did; otherwise the text.
fn print_report(
    report: &FlightReport,
    predicted: bool,
    json: bool,
    simulator: Option<&SimSummary>,
) -> anyhow::Result<()> {
    if json {
        let lfs_motion_model = predicted.then(|| prediction_model(report.mode));
        return super::print_json(&FlyJson {
            report,
            lfs_motion_model,
            simulator,
        });
    }
    print_text(report);
    if let Some(s) = simulator {
        println!("simulator         {s}");
    }
    Ok(())
}

/// `fly --json`: the flight's report, the motion model of the LFS prediction and the simulator beside it.
#[derive(serde::Serialize)]
struct FlyJson<'a> {
    #[serde(flatten)]
    report: &'a FlightReport,
    /// `null` when there is no prediction (`--no-predict`, or it failed).
    lfs_motion_model: Option<&'static str>,
    /// prgenuav's simulator (`--sim iris`, `--hitl`); `null` otherwise.
    simulator: Option<&'a SimSummary>,
}

/// The LFS model that predicted a flight of `mode`.
fn prediction_model(mode: FlyMode) -> &'static str {
    match mode {
        FlyMode::CollisionPrevention => "collision-prevention",
        _ => PREDICTION_MOTION.model().name(),
    }
}

/// Writes the Gazebo world of the test's boxes where `--world` asks; whether it did.
fn write_world(args: &FlyArgs, test: &TestCase) -> anyhow::Result<bool> {
    let Some(path) = &args.world else { return Ok(false) };
    write_atomic(path, world_sdf(&test.obstacles).as_bytes()).with_context(|| format!("writing {}", path.display()))?;
    Ok(true)
}

/// Where a re-anchored test's boxes went (`--anchor-at-vehicle-home`).
fn print_anchoring(report: &FlightReport) {
    if let Some(p) = report.placement.as_ref().filter(|p| p.anchored) {
        eprintln!(
            "re-anchored at the vehicle's home {:.7}, {:.7} ({:.1} m AMSL), {:.0} m from the test's home",
            p.vehicle_home.lat_deg, p.vehicle_home.lon_deg, p.vehicle_home.alt_m, p.distance_m
        );
        for (i, c) in p.obstacle_centres.iter().enumerate() {
            eprintln!("  box {i} centre now at {:.7}, {:.7}", c.lat_deg, c.lon_deg);
        }
    }
}

/// 0: flown to the end (landed or collided: a measurement); 1: the flight did not complete; 2: the vehicle
/// stands too far from the test's home to fly it without --anchor-at-vehicle-home.
fn exit_code(report: &FlightReport) -> ExitCode {
    let too_far = report.placement.as_ref().is_some_and(|p| p.too_far);
    match report.status {
        Status::Landed | Status::Collision => ExitCode::SUCCESS,
        Status::Rejected if too_far => ExitCode::from(super::EXIT_ERROR),
        _ => ExitCode::from(super::EXIT_FAIL),
    }
}

/// The bridge's options from the flags, checked before anything is contacted.
fn options(args: &FlyArgs, flight: &Flight, prediction: Option<&Prediction>) -> anyhow::Result<FlyOptions> {
    let opts = FlyOptions {
        connect: args.connect.clone(),
        mode: flight.mode,
        timeout_s: flight.timeout_s,
        trajectory_csv: args.trajectory.clone(),
        fence: !args.no_fence,
        time_scale: limits::FLY_TIME_SCALE.check(args.time_scale.unwrap_or(if flight.px4.is_some() {
            flight.px4_speed_factor
        } else {
            1.0
        }))?,
        lfs_min_distance: prediction.and_then(|p| p.min_distance),
        lockstep: match args.lockstep {
            None => None,
            Some(ms) if ms.is_finite() && (0.0..=1000.0).contains(&ms) => Some(Duration::from_secs_f64(ms / 1000.0)),
            Some(ms) => anyhow::bail!("--lockstep {ms}: expected a latency of 0 to 1000 ms"),
        },
        judge: flight.judge,
        anchor_at_vehicle_home: flight.anchor_at_vehicle_home,
        ready_timeout_s: limits::FLY_READY_TIMEOUT.check(args.ready_timeout)?,
        // Quiet or not, a listener: the vehicle is asked for its version, which the report names.
        notices: Some(if args.quiet {
            NoticeSink::new(|_| {})
        } else {
            NoticeSink::new(|n| eprintln!("{n}"))
        }),
        ..FlyOptions::default()
    };
    opts.validate()?;
    Ok(opts)
}

/// `--plot`: the flown path over the predicted one.
fn write_plot(
    path: &Path,
    test: &TestCase,
    prediction: Option<&Prediction>,
    report: &FlightReport,
    mode: FlyMode,
) -> anyhow::Result<()> {
    let mut plot = FlightPlot::new(test);
    if let Some(p) = prediction {
        plot.add_path(&p.trajectory, PathStyle::Simulated, "LFS prediction");
    }
    let mode = super::wording::words(&format!("{mode:?}"));
    plot.add_path(&report.trajectory, PathStyle::Flown, &format!("flown ({mode})"));
    if let Some(c) = &report.closest_approach {
        plot.mark_closest(c);
    }
    write_atomic(path, plot.to_svg().as_bytes()).with_context(|| format!("writing {}", path.display()))
}

fn print_text(report: &FlightReport) {
    let m = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3} m"));
    println!(
        "status            {}{}",
        report.status.as_str(),
        report.reason.as_deref().map(|r| format!(" ({r})")).unwrap_or_default()
    );
    println!(
        "min_distance      {} (judge {}: 0.5 s bins; {})",
        m(report.min_distance),
        report.judge,
        report.judge_definition
    );
    if let (Some(src), Some([n, e])) = (report.frame_source, report.frame_origin_offset_m) {
        println!(
            "frame             {} (from {}: EKF origin at N {n:.2} m, E {e:.2} m)",
            report.frame,
            super::wording::words(&format!("{src:?}"))
        );
    }
    if let Some(v) = &report.vehicle {
        println!("vehicle           {v}");
    }
    println!("min_distance_raw  {}", m(report.min_distance_raw));
    print_cp(report);
    let model = prediction_model(report.mode);
    println!(
        "lfs_min_distance  {} (the LFS prediction, {model} motion model)",
        m(report.lfs_min_distance)
    );
    print_closest(report);
    println!(
        "flight            {:.1} s, {} positions; link {} packets, {} retries; fence {}",
        super::wording::non_negative(report.flight_time_s),
        report.samples,
        report.link.packets_received,
        report.link.retries,
        if report.fence_uploaded {
            "on the vehicle"
        } else {
            "not uploaded"
        }
    );
    print_notes(report);
}

/// Each obstacle's distance and where the path came closest, above a box's top or not.
fn print_closest(report: &FlightReport) {
    for d in &report.per_obstacle {
        println!(
            "  obstacle {}: {:.3} m (raw {:.3} m)",
            d.index, d.distance, d.distance_raw
        );
    }
    if let Some(c) = &report.closest_approach {
        println!(
            "closest approach  t = {:.2} s at x = {:.2}, y = {:.2}, z = {:.2} (obstacle {})",
            super::wording::non_negative(c.t_s),
            c.x,
            c.y,
            c.z,
            c.obstacle
        );
    }
    if let Some(a) = report.above_top {
        println!(
            "above the top     of obstacle {} by {:.2} m at the closest approach (the distance is horizontal)",
            a.obstacle, a.height_m
        );
    }
}

/// A Collision Prevention flight's verdict: `CP_DIST` kept or not, and the competition's points.
fn print_cp(report: &FlightReport) {
    let m = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3} m"));
    let Some(cp) = &report.collision_prevention else { return };
    let points = report
        .min_distance
        .map_or("-".into(), |d| prgenuav::judge::points(d).to_string());
    let inside = match cp.inside_cp_dist {
        Some(true) => "came inside CP_DIST",
        Some(false) => "kept CP_DIST",
        None => "not measured",
    };
    println!(
        "collision_prev.   {inside} {:.2} m (closest centre {}); points {points}",
        cp.cp_dist_m,
        m(cp.closest_centre_m)
    );
}

/// The flight's side notes: how long the vehicle took to be ready, the clock, the companion, warnings.
fn print_notes(report: &FlightReport) {
    if let Some(w) = report.ready_wait_s {
        println!("ready after       {w:.1} s");
    }
    if let Some(w) = report.clock.as_ref().and_then(|c| c.warning.as_ref()) {
        println!("clock             {w}");
    }
    if let Some(t) = &report.companion_timing {
        println!("companion         {t}");
    }
    for w in &report.warnings {
        println!("warning           {w}");
    }
}
