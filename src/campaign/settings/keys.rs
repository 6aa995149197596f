//! The declaration of the settings only the command line gives: what the campaign is (`[campaign]`: the case,
//! the budget, the seed, the mode, the judge, the prior) and what flies it (`[vehicles]`: the embedded mocks,
//! MAVLink URLs, PX4 SITL instances started here, or runner jobs).

use std::path::PathBuf;

use super::declare::section;
use super::rules;
use super::{Flag, Resume};
use crate::bridge::{Bench, FlyMode, SimLink, VehicleSim};
use crate::judge::Judge;
use crate::model::Limit;

/// The largest budget accepted. A campaign keeps its journal in memory (about 1 KB a flight) and the report
/// compares failing tests pairwise, so 10,000 flights stay small; on the mock they take about 5 hours.
pub const MAX_BUDGET: usize = 10_000;
/// The most candidates accepted. Each is screened by a full low-fidelity flight (about 0.2 s of one core), so
/// 100,000 are hours of screening; they are held as a few hundred bytes each.
pub const MAX_CANDIDATES: usize = 100_000;
/// The largest speed-up of simulated time: beyond it a vehicle's physics step outruns any link.
pub const MAX_TIME_SCALE: f64 = 1000.0;
/// Runner jobs at once, at most: each is a thread and a local process (`sh -c`, `srun`, `kubectl`, ...).
pub const MAX_JOBS: usize = 1024;
/// `--jobs` with `--runner` (on the mocks it has `mock.vehicles`' range, on PX4 `--instances`').
pub const RUNNER_JOBS: Limit = Limit::count(1, MAX_JOBS, "(each job is a thread and a local process)");

section! {
    /// `[campaign]`: what the campaign is.
    Campaign, CampaignAsked, "campaign", CAMPAIGN {
        case: PathBuf = [required "missions/mission2.yaml"] {
            flag: Some(Flag::positional("case", "CASE", 1)),
            help: "The case study YAML (mission, params, commands).",
        },
        budget: usize = [required "100"] {
            flag: Some(Flag::positional("budget", "BUDGET", 2)),
            range: Some(Limit::count(1, MAX_BUDGET, "flights")),
            help: "High-fidelity flights allowed (the competition's budget): 1 to 10000.",
        },
        seed: u64 = [value 0] {
            flag: Some(Flag::value("--seed", "S").short('s').visible()),
            help: "Seed of every random draw: the same seed draws the same candidates (and, with --sim iris, the same \
                   sensor noise of each flight).",
        },
        mode: FlyMode = [value FlyMode::Avoidance] {
            flag: Some(Flag::value("--mode", "MODE")),
            help: "How the flights avoid the virtual obstacles.",
        },
        judge: Judge = [value Judge::E2026] {
            flag: Some(Flag::value("--judge", "EDITION").visible()),
            help: "Judge edition of the distances (and of the low-fidelity prediction).",
        },
        prior: PathBuf = [absent "none: the campaign starts from the shipped calibration", "results/2026-11-29T03-20-58"] {
            flag: Some(Flag { conflicts_with: "no-learn", ..Flag::value("--prior", "FOLDER").visible() }),
            help: "Start from what an earlier campaign learnt (its output folder's learnt.json).",
        },
    }
}

section! {
    /// `[vehicles]`: what flies the campaign.
    Vehicles, VehiclesAsked, "vehicles", VEHICLES {
        connect: Vec<String> = [value vec!["mock".to_string()]] {
            flag: Some(Flag { alias: "hfs", ..Flag::value("--connect", "mock|URL,...").visible() }),
            help: "The vehicles: `mock` (embedded mock autopilots) or MAVLink URLs separated by commas, one flight per \
                   vehicle at a time (e.g. udpin:0.0.0.0:14540,udpin:0.0.0.0:14541).",
        },
        runner: String = [absent "none: the flights go to the vehicles of `connect` or `px4`", "srun {test}"] {
            flag: Some(Flag { conflicts_with: "connect", ..Flag::value("--runner", "COMMAND").visible() }),
            help: "Fly each test as a job of an existing engine: this shell command, run per flight in the flight's \
                   job folder with {test} (its test YAML), {dir} (the folder) and {id} filled in; the flight is read \
                   back from what the job leaves there (docs/runners.md: Aerialist, Slurm, Kubernetes).",
        },
        jobs: usize = [absent "the backend's own: one per core on the mocks, what the cores carry on --px4, 1 runner job", "2"] {
            flag: Some(Flag::value("--jobs", "N").short('j').visible()),
            resume: Resume::Inherited,
            help: "Flights at once, whatever flies them: embedded mocks (default: one per core), --px4 instances \
                   (default: what the cores carry) or --runner jobs (default 1).",
        },
        job_timeout_s: f64 = [value 1200.0] {
            flag: Some(Flag::value("--job-timeout", "S")),
            range: Some(Limit::above(0.0, 604_800.0, "s")),
            resume: Resume::Asked,
            help: "Wall-time limit of one runner job, seconds (with --runner).",
        },
        runner_cancel: String = [absent "none: a stopped job is left to its engine", "scancel --name {id}"] {
            flag: Some(Flag::value("--runner-cancel", "COMMAND")),
            resume: Resume::Asked,
            help: "With --runner: the command that cancels a job in its engine when the campaign stops or the job \
                   times out, with {id} (`scancel --name {id}`; docs/runners.md). Not kept: give it again with \
                   --resume.",
        },
        px4: PathBuf = [absent "none: no PX4 is started here", "/path/to/PX4-Autopilot/build/px4_sitl_default"] {
            flag: Some(Flag { conflicts_with: "connect", ..Flag::value("--px4", "BUILD_DIR").visible() }),
            help: "Fly on PX4 SITL instances started here, every flight on a fresh instance at the test's home: \
                   BUILD_DIR is your PX4-Autopilot `build/px4_sitl_default` folder (docs/px4.md).",
        },
        instances: usize = [absent "what the machine's cores carry at the speed factor (docs/px4.md)", "2"] {
            flag: Some(Flag::value("--instances", "K")),
            range: Some(Limit::count(1, crate::bridge::sitl::slot::SLOTS as usize, "PX4 instances (docs/px4.md)")),
            resume: Resume::Asked,
            help: "PX4 instances flying at once (default: what the machine's cores carry at --speed-factor, \
                   docs/px4.md); --jobs says the same.",
        },
        speed_factor: f64 = [value 5.0] {
            flag: Some(Flag::value("--speed-factor", "F")),
            range: Some(Limit::above(0.0, 100.0, "x wall time")),
            help: "PX4_SIM_SPEED_FACTOR of the --px4 instances (the factor the PX4 campaigns of docs/experiments.md \
                   flew at).",
        },
        keep_ulog: bool = [value false] {
            flag: Some(Flag::switch("--keep-ulog", true)),
            help: "Copy each --px4 flight's ULog beside its trajectory, flights/candidate_N.ulg.",
        },
        bench: Bench = [value Bench::Plain] {
            flag: Some(Flag::value("--bench", "BENCH")),
            help: "What the --px4 instances reproduce: `plain` (the build, --sim and the test's parameters as given) \
                   or `competition` (the competition's simulator as far as prgenuav reproduces it: PX4 v1.12 only, \
                   prgenuav's iris facing East at rest as Gazebo spawns it, and MPC_XY_CRUISE 2.3, chosen by \
                   cross-validation on the competition's recorded flights; docs/validation/competition-bench-fit.md).",
        },
        sim: VehicleSim = [rule rules::sim, "the bench's: iris with --bench competition, else sih", "iris"] {
            flag: Some(Flag::value("--sim", "SIM")),
            help: "What simulates the vehicle of the --px4 instances: `sih` (PX4's own, v1.14 on) or `iris` \
                   (prgenuav's Gazebo-Classic iris in this process, PX4 in external-simulator mode, v1.12 on; in \
                   lockstep the avoidance companion runs on simulated time, so no flight starves; docs/px4.md).",
        },
        sim_link: SimLink = [value SimLink::Tcp] {
            flag: Some(Flag::value("--sim-link", "LINK")),
            help: "With --sim iris: the simulator's HIL link to PX4, `tcp` (PX4's connection, in lockstep) or \
                   `serial` (a pty joined to PX4's TCP port by socat, on the wall clock at 250 Hz, as a board's; \
                   real time only).",
        },
        hitl: Vec<String> = [absent "none: no board in the loop", "serial:/dev/ttyACM0:921600"] {
            flag: Some(Flag {
                conflicts_with: "px4",
                ..Flag::value("--hitl", "serial:DEVICE:BAUD,...")
            }),
            resume: Resume::Inherited,
            help: "Fly flight controllers on a bench in the loop (HITL), one per serial URL: prgenuav's simulator \
                   feeds each board its sensors over that port on the wall clock and the flight goes through the \
                   simulator's gateway. Each board must run SYS_HITL 1 (airframe 1001, firmware with pwm_out_sim; \
                   docs/hitl.md).",
        },
    }
}
