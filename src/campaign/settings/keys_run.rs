//! The declaration of the settings of a campaign's run: screening, the embedded mocks, every flight, learning.

use super::keys::{DEFAULT_MOCK_LATENCY_MS, MAX_CANDIDATES, MAX_TIME_SCALE, MOCKS_PER_CORE, section};
use super::{DefaultValue, Flag, FlagText, Setting};
use crate::campaign::settings::mock_profile::DEFAULT_PROFILE;
use crate::lfs::eval::ensemble::MAX_MEMBERS;
use crate::model::Limit;

use super::keys::BLANK;

section! {
    /// `[screening]`.
    Screening, "screening", SCREENING {
        candidates: usize = [setup "3 x BUDGET, at least 20", "60"] {
            flag: Some(Flag::value("--candidates", "N")),
            stored: "candidates",
            range: Some(Limit::count(1, MAX_CANDIDATES, "")),
            help: "Candidates to draw and screen with the low-fidelity simulator.",
        },
        threshold_m: f64 = [value 3.0] {
            flag: Some(Flag::value("--threshold", "M")),
            stored: "threshold_m",
            range: Some(Limit::above(0.0, 100.0, "m")),
            help: "Fly only candidates the simulator predicts closer than this, metres.",
        },
        max_iou: f64 = [value 0.5] {
            flag: Some(Flag::value("--max-iou", "IOU")),
            stored: "max_iou",
            range: Some(Limit::within(0.0, 1.0, "")),
            help: "Skip a candidate whose footprints overlap an already chosen one by more than this IoU.",
        },
        motion: String = [value "px4".to_string()] {
            flag: Some(Flag::value("--motion", "MOTION")),
            stored: "motion",
            choices: &[
                ("px4", "PX4's waypoint generator and a PX4-like position tracker."),
                ("paper", "The paper's kinematic rule towards the planner's first tree node."),
            ],
            help: "The simulator's motion model: `px4` or `paper`.",
        },
        ensemble: usize = [setup "0 with mock vehicles, 8 with MAVLink ones", "0"] {
            flag: Some(Flag::value("--ensemble", "N")),
            stored: "ensemble",
            range: Some(Limit::count(0, MAX_MEMBERS, "members")),
            help: "Members of the simulator ensemble run on the 2 x BUDGET most severe candidates, which are then \
                   flown in order of expected points per minute; 0 ranks by the point prediction. An ensemble costs \
                   about 1 s of CPU per candidate: more than a mock flight, far less than a PX4 or hardware flight.",
        },
        screen: bool = [value true] {
            flag: Some(Flag::switch("--no-screen", false).helped(
                "Skip the simulator: fly candidates in the order drawn (screening.screen = false).",
            )),
            stored: "screen",
            help: "`false` skips the simulator and flies candidates in the order drawn (the baseline that shows what \
                   screening buys); it also turns learning off.",
        },
    }
}

section! {
    /// `[mock]`.
    Mock, "mock", MOCK {
        speed: f64 = [value 100.0] {
            flag: Some(Flag::value("--mock-speed", "K")),
            stored: "mock_speed",
            range: Some(Limit::within(1.0, MAX_TIME_SCALE, "x wall time")),
            help: "Clock speed of the embedded mock autopilots, times real time; in lockstep an upper bound. Not \
                   given: 20 in collision-prevention mode (the speed its pilot's sticks keep up with).",
        },
        lockstep: bool = [value true] {
            flag: Some(Flag::switch("--mock-free-running", false).helped(
                "Let the embedded mocks' clocks run free, no lockstep (mock.lockstep = false).",
            )),
            stored: "mock_lockstep",
            help: "The mock holds its clock until each avoidance answer, so flights do not depend on the CPU. \
                   `false` lets the clocks run free, as on a real vehicle (use a low speed, e.g. 20, with it).",
        },
        latency_ms: f64 = [value DEFAULT_MOCK_LATENCY_MS] {
            flag: Some(Flag::value("--mock-latency", "MS")),
            stored: "mock_latency_ms",
            range: Some(Limit::within(0.0, 1000.0, "ms")),
            help: "In lockstep, the companion plans on the pose this many vehicle milliseconds old.",
        },
        vehicles: usize = [setup "one per core", "2"] {
            flag: Some(Flag::value("--mock-vehicles", "N")),
            range: Some(Limit::count_per_core(1, MOCKS_PER_CORE, "")),
            help: "Embedded mock autopilots flying at once. Flights mostly wait on the mock's clock, so more \
                   vehicles than cores can help while the planner keeps up. Not stored: a resumed campaign may \
                   change it.",
        },
        profile: String = [value DEFAULT_PROFILE.to_string()] {
            flag: Some(Flag::value("--mock-profile", "NAME")),
            stored: "mock_profile",
            help: "What the embedded mocks' avoidance flights are fitted to: `px4-sitl` (real PX4 v1.14 SITL) or \
                   `competition` (the competition's recorded Gazebo flights); see docs/mock-autopilot.md.",
        },
    }
}

section! {
    /// `[flight]`.
    Flight, "flight", FLIGHT {
        timeout_s: f64 = [value crate::bridge::FlyOptions::default().timeout_s] {
            flag: Some(Flag::value("--timeout", "S")),
            stored: "flight_timeout_s",
            range: Some(Limit::above(0.0, 86_400.0, "s")),
            help: "Give a flight up (LAND) after this many vehicle seconds.",
        },
        connect_timeout_s: f64 = [value 15.0] {
            flag: Some(Flag::value("--connect-timeout", "S")),
            range: Some(Limit::above(0.0, 3600.0, "s")),
            help: "Seconds to wait for each MAVLink vehicle's first heartbeat. Not stored: a resumed campaign may \
                   change it.",
        },
        connect_time_scale: f64 = [setup "measured on each vehicle as it connects", "1.0"] {
            flag: Some(Flag { alias: "hfs-time-scale", ..Flag::value("--connect-time-scale", "K") }),
            stored: "hfs_time_scale",
            range: Some(Limit::above(0.0, MAX_TIME_SCALE, "x wall time")),
            help: "Clock rate of the `--connect` vehicles (PX4_SIM_SPEED_FACTOR).",
        },
        anchor_at_vehicle_home: bool = [value false] {
            flag: Some(Flag::switch("--anchor-at-vehicle-home", true).helped(
                "Re-anchor every test at each vehicle's home (flight.anchor_at_vehicle_home).",
            )),
            stored: "anchor_at_vehicle_home",
            help: "Re-anchor every test (mission, obstacles, fence) at each vehicle's home instead of refusing a \
                   vehicle farther from the test's home than its MIS_DIST_1WP (bench drones anywhere).",
        },
        confirm: usize = [setup "3; 1 on the embedded mock without gusts (the `competition` profile, or outside \
                                 avoidance mode)", "3"] {
            flag: Some(Flag::value("--confirm", "K").shown(
                "Flights a failing test gets at most: it is flown again until the majority of K flights is \
                 settled; the re-flights narrow the estimate of its expected 2026 points, by which tests are \
                 written (default: 3; 1 on the embedded mock's gust-free `competition` profile, whose flights \
                 repeat; 1 flies every test once).",
            )),
            stored: "confirm",
            range: Some(Limit::count(1, 20, "flights per test")),
            help: "Flights a failing test gets at most (K, at least 1). A test whose flight fails is flown again, \
                   before any new candidate and within the budget, until the majority of K flights is settled (K = \
                   3: two failures or two passes). Its flights narrow the estimate of its expected 2026 points: a test \
                   is written as `test_N.yaml` when the 10 % bound of that estimate is above zero (docs/campaign.md); \
                   the others that failed go to `unconfirmed.json`. 1 flies every test once.",
        },
        overlap: bool = [setup "true with --connect, --px4 and --runner vehicles, false with the embedded mock",
                         "false"] {
            stored: "overlap",
            help: "Plan each learning round (draw, screen, ensemble, rank) while the previous one flies, so the \
                   vehicles do not wait on the simulator; each round then learns from the flights before the \
                   previous round (one round of lag). The embedded mock flies on the same cores as the screening, \
                   so it gains nothing there.",
        },
    }
}

section! {
    /// `[learning]`.
    Learning, "learning", LEARNING {
        learn: bool = [value true] {
            flag: Some(Flag::switch("--no-learn", false).shown(
                "Do not learn: screen once, fly the ranking (the static campaign). By default the campaign flies in \
                 rounds, calibrating the simulator on every flight and adapting the generator towards failures.",
            )),
            stored: "learn",
            help: "Fly in rounds (8, up to 12 while near-duplicates leave budget unflown), calibrating the simulator \
                   on every flight. `false`: screen once and fly the ranking (the static campaign).",
        },
        adapt: bool = [value true] {
            flag: Some(Flag {
                conflicts_with: "no-learn",
                ..Flag::switch("--no-adapt", false).helped(
                    "Learn the simulator's calibration but keep the paper's uniform draws (learning.adapt = false).",
                )
            }),
            stored: "adapt",
            help: "While learning, also adapt the generator towards failures (draws around failing flights, a draw \
                   distribution moved towards the best candidates). `false` keeps the paper's uniform draws.",
        },
        min_diversity: f64 = [value 0.8] {
            flag: Some(Flag::value("--min-diversity", "D")),
            stored: "min_diversity",
            range: Some(Limit::within(0.0, 1.0, "")),
            help: "Floor of the failing tests' diversity (1 - mean pairwise IoU): the adapted generator draws and \
                   flies only candidates that keep the expected final diversity above it.",
        },
        child_max_iou: f64 = [value 0.85] {
            flag: Some(Flag::value("--child-max-iou", "IOU")),
            stored: "child_max_iou",
            range: Some(Limit::within(0.0, 1.0, "")),
            help: "A candidate drawn next to a failing flight may overlap a flown test up to this IoU (more than \
                   `max_iou`) while the failing tests would keep `min_diversity`: near copies of a failure fail \
                   most often. Set it to `max_iou` to hold every candidate to `max_iou`.",
        },
    }
}
