//! What `fly` starts for its one flight and stops after it: a PX4 SITL instance on a free slot (SIH, or
//! external-simulator mode with prgenuav's iris simulator in this process: `--px4 BUILD --sim iris`), or the
//! simulator on a board's serial port (`--hitl serial:DEVICE:BAUD`), and how the bridge reaches it.

use prgenuav::bridge::hil::board::{Board, BoardPort};
use prgenuav::bridge::hil::run::SimSummary;
use prgenuav::bridge::hil::sitl::{IrisSitl, IrisSpec};
use prgenuav::bridge::sitl::slot::{self, Slot};
use prgenuav::bridge::sitl::{BOOT_TIMEOUT, Px4Build, Px4Sitl, SitlSpec};
use prgenuav::bridge::{Bench, FlyMode, FlyOptions, SimLink, VehicleSim};
use prgenuav::model::TestCase;
use std::sync::atomic::AtomicBool;
use std::time::Duration;
use tokio::runtime::Runtime;

/// How the flight's vehicle is simulated, as `fly`'s settings say.
pub struct Simulated {
    /// What simulates a `--px4` instance.
    pub sim: VehicleSim,
    /// The iris simulator's link to PX4.
    pub link: SimLink,
    /// The simulator's seed.
    pub seed: u64,
    /// What the flight reproduces.
    pub bench: Bench,
}

/// `--px4 DIR`: the checked build folder, refused when its release cannot fly `mode` as `sim` says.
pub fn open_build(dir: &std::path::Path, mode: FlyMode, sim: &Simulated) -> anyhow::Result<Px4Build> {
    let build = Px4Build::open(dir)?;
    build.check_mode(mode)?;
    if let Some(why) = sim.bench.sim_refusal(sim.sim) {
        anyhow::bail!(why);
    }
    build.check_bench(sim.bench)?;
    build.check_sim(sim.sim)?;
    Ok(build)
}

/// What runs for the flight; stopped by [`Started::finish`] (or when dropped), the slot freed last.
pub enum Started {
    /// Nothing: a vehicle the user started.
    Nothing,
    /// PX4 SIH.
    Sih(Px4Sitl, Slot),
    /// PX4 with prgenuav's simulator.
    Iris(Box<IrisSitl>, Slot),
    /// prgenuav's simulator on a board.
    Board(Board),
}

/// `--px4`: a fresh instance at the test's home on a free instance slot (held until the flight ends, so
/// parallel `fly --px4` jobs on one machine do not share ports), booted; `opts` then fly it. Started on the
/// calling thread, which must outlive the flight (PX4 dies with the thread that started it).
pub fn start_px4(
    rt: &Runtime,
    build: &Px4Build,
    sim: &Simulated,
    test: &TestCase,
    opts: &mut FlyOptions,
    quiet: bool,
) -> anyhow::Result<Started> {
    let speed = opts.time_scale;
    let slot = slot::claim_with(0, sim.sim)?;
    let i = slot.instance();
    if !quiet {
        let how = match sim.sim {
            VehicleSim::Sih => "SIH".to_string(),
            VehicleSim::Iris => format!(
                "with prgenuav's iris simulator (seed {}, {:?} link)",
                sim.seed, sim.link
            ),
        };
        eprintln!(
            "starting PX4 {} instance {i} {how} at the test's home, speed factor {speed} ...",
            build.version
        );
    }
    opts.detect_time_scale = true;
    opts.target_system = Some(i.saturating_add(1));
    if sim.sim == VehicleSim::Sih {
        let px4 = Px4Sitl::start(&SitlSpec::for_build(build, i, speed).at(test.home))?;
        opts.connect = px4.url();
        return Ok(Started::Sih(px4, slot));
    }
    let tcp = sim.link == SimLink::Tcp;
    let spec = IrisSpec {
        build: build.clone(),
        instance: i,
        home: test.home,
        heading_deg: sim.bench.heading_deg(),
        seed: sim.seed,
        speed_factor: speed,
        link: sim.link,
        paced: tcp && opts.mode == FlyMode::Avoidance,
        boot_timeout: BOOT_TIMEOUT,
    };
    let iris = IrisSitl::start(rt.handle(), &spec, &AtomicBool::new(false))?;
    opts.connect = iris.px4.url();
    opts.sim_gate = iris.gate();
    if tcp {
        opts.lockstep = Some(Duration::ZERO);
    } else {
        opts.time_scale = 1.0;
    }
    Ok(Started::Iris(Box::new(iris), slot))
}

/// `--hitl`: prgenuav's simulator on the board's serial port, the bridge flying it through the gateway on the
/// wall clock, refused unless the board is in HITL mode.
pub fn start_board(
    rt: &Runtime,
    port: &BoardPort,
    seed: u64,
    test: &TestCase,
    opts: &mut FlyOptions,
    quiet: bool,
) -> anyhow::Result<Started> {
    if !quiet {
        eprintln!(
            "feeding the board on {} at {} baud with prgenuav's iris simulator (wall clock, 250 Hz) ...",
            port.device, port.baud
        );
    }
    let board = rt.block_on(Board::start(port, test.home, seed))?;
    opts.connect = board.url().to_string();
    opts.require_hitl = true;
    opts.time_scale = 1.0;
    Ok(Started::Board(board))
}

impl Started {
    /// PX4's last console lines, when prgenuav started PX4.
    pub fn console_tail(&self, n: usize) -> Option<Vec<String>> {
        match self {
            Started::Sih(px4, _) => Some(px4.console_tail(n)),
            Started::Iris(iris, _) => Some(iris.px4.console_tail(n)),
            Started::Nothing | Started::Board(_) => None,
        }
    }

    /// Stops everything (the simulator first, so its port is free, then PX4, then the slot); what the
    /// simulator did, if one ran.
    pub fn finish(self, rt: &Runtime) -> Option<SimSummary> {
        match self {
            Started::Nothing => None,
            Started::Sih(px4, slot) => {
                drop(px4); // the instance is gone before its slot is freed
                drop(slot);
                None
            }
            Started::Iris(mut iris, slot) => {
                let summary = iris.finish();
                drop(iris);
                drop(slot);
                summary
            }
            Started::Board(board) => Some(rt.block_on(board.stop())),
        }
    }
}
