//! The declaration of the settings of a campaign's flights: the embedded mocks (`[mock]`), every flight
//! (`[flight]`) and learning between rounds (`[learning]`).

use super::declare::section;
use super::keys::MAX_TIME_SCALE;
use super::mock_profile::ProfileName;
use super::rules;
use super::{Flag, Resume};
use crate::model::Limit;

/// Fitted against the recorded competition flights: any pose age only adds clearance, so none is modelled
/// (docs/design-constants.md#mock-pose-latency).
pub const DEFAULT_MOCK_LATENCY_MS: f64 = 0.0;
/// Embedded mock autopilots per core, at most: each simulates and judges a flight on the campaign's threads.
pub const MOCKS_PER_CORE: usize = 8;

section! {
    /// `[mock]`.
    Mock, MockAsked, "mock", MOCK {
        speed: f64 = [rule rules::mock_speed, "100; 20 in collision-prevention mode (the speed its pilot's sticks \
                                             keep up with)", "100.0"] {
            flag: Some(Flag::value("--mock-speed", "K")),
            range: Some(Limit::within(1.0, MAX_TIME_SCALE, "x wall time")),
            help: "Clock speed of the embedded mock autopilots, times real time; in lockstep an upper bound.",
        },
        lockstep: bool = [value true] {
            flag: Some(Flag::switch("--mock-free-running", false).helped(
                "Let the embedded mocks' clocks run free, no lockstep (mock.lockstep = false).",
            )),
            help: "The mock holds its clock until each avoidance answer, so flights do not depend on the CPU. \
                   `false` lets the clocks run free, as on a real vehicle (use a low speed, e.g. 20, with it).",
        },
        latency_ms: f64 = [value DEFAULT_MOCK_LATENCY_MS] {
            flag: Some(Flag::value("--mock-latency", "MS")),
            range: Some(Limit::within(0.0, 1000.0, "ms")),
            help: "In lockstep, the companion plans on the pose this many vehicle milliseconds old.",
        },
        vehicles: usize = [rule rules::mock_vehicles, "as many as --jobs, else one per core", "2"] {
            flag: Some(Flag::value("--mock-vehicles", "N")),
            range: Some(Limit::count_per_core(1, MOCKS_PER_CORE, "")),
            resume: Resume::Asked,
            help: "Embedded mock autopilots flying at once. Flights mostly wait on the mock's clock, so more \
                   vehicles than cores can help while the planner keeps up. A resumed campaign takes it as asked \
                   again.",
        },
        profile: ProfileName = [value ProfileName::Px4Sitl] {
            flag: Some(Flag::value("--mock-profile", "NAME")),
            help: "What the embedded mocks' avoidance flights are fitted to: `px4-sitl` (real PX4 v1.14 SITL) or \
                   `competition` (the competition's recorded Gazebo flights); see docs/mock-autopilot.md.",
        },
        gust_acc_m_s2: f64 = [rule rules::gusts, "the profile's (px4-sitl 0.1, competition 0)", "0.1"] {
            range: Some(Limit::within(0.0, 10.0, "m/s² per horizontal axis")),
            help: "RMS of the embedded mocks' seeded horizontal gusts in avoidance mode: how much the mock disagrees \
                   with itself flight to flight (docs/design-constants.md#px4-sitl-gusts).",
        },
    }
}

section! {
    /// `[flight]`.
    Flight, FlightAsked, "flight", FLIGHT {
        timeout_s: f64 = [value crate::bridge::FlyOptions::default().timeout_s] {
            flag: Some(Flag::value("--timeout", "S")),
            range: Some(Limit::above(0.0, 86_400.0, "s")),
            help: "Give a flight up (LAND) after this many vehicle seconds.",
        },
        connect_timeout_s: f64 = [value 15.0] {
            flag: Some(Flag::value("--connect-timeout", "S")),
            range: Some(Limit::above(0.0, 3600.0, "s")),
            resume: Resume::Asked,
            help: "Seconds to wait for each MAVLink vehicle's first heartbeat. A resumed campaign takes it as \
                   asked again.",
        },
        connect_time_scale: f64 = [absent "measured on each vehicle as it connects", "1.0"] {
            flag: Some(Flag { alias: "hfs-time-scale", ..Flag::value("--connect-time-scale", "K") }),
            range: Some(Limit::above(0.0, MAX_TIME_SCALE, "x wall time")),
            help: "Clock rate of the `--connect` vehicles (PX4_SIM_SPEED_FACTOR).",
        },
        anchor_at_vehicle_home: bool = [value false] {
            flag: Some(Flag::switch("--anchor-at-vehicle-home", true).helped(
                "Re-anchor every test at each vehicle's home (flight.anchor_at_vehicle_home).",
            )),
            help: "Re-anchor every test (mission, obstacles, fence) at each vehicle's home instead of refusing a \
                   vehicle farther from the test's home than its MIS_DIST_1WP (bench drones anywhere).",
        },
        confirm: usize = [rule rules::confirm, "3; 1 on the embedded mock without gusts (the `competition` profile, \
                                               or outside avoidance mode)", "3"] {
            flag: Some(Flag::value("--confirm", "K").shown(
                "Flights a failing test gets at most: it is flown again until the majority of K flights is \
                 settled; the re-flights narrow the estimate of its expected 2026 points, by which tests are \
                 written (default: 3; 1 on the embedded mock's gust-free `competition` profile, whose flights \
                 repeat; 1 flies every test once).",
            )),
            range: Some(Limit::count(1, 20, "flights per test")),
            help: "Flights a failing test gets at most (K, at least 1). A test whose flight fails is flown again, \
                   before any new candidate and within the budget, until the majority of K flights is settled (K = \
                   3: two failures or two passes). Its flights narrow the estimate of its expected 2026 points: a test \
                   is written as `test_N.yaml` when the 10 % bound of that estimate is above zero (docs/campaign.md); \
                   the others that failed go to `unconfirmed.json`. 1 flies every test once.",
        },
        overlap: bool = [rule rules::overlap, "true with --connect, --px4 and --runner vehicles, false with the \
                                               embedded mock", "false"] {
            help: "Plan each learning round (draw, screen, ensemble, rank) while the previous one flies, so the \
                   vehicles do not wait on the simulator; each round then learns from the flights before the \
                   previous round (one round of lag). The embedded mock flies on the same cores as the screening, \
                   so it gains nothing there.",
        },
    }
}

section! {
    /// `[learning]`.
    Learning, LearningAsked, "learning", LEARNING {
        learn: bool = [value true] {
            flag: Some(Flag::switch("--no-learn", false).shown(
                "Do not learn: screen once, fly the ranking (the static campaign). By default the campaign flies in \
                 rounds, calibrating the simulator on every flight and adapting the generator towards failures.",
            )),
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
            help: "While learning, also adapt the generator towards failures (draws around failing flights, a draw \
                   distribution moved towards the best candidates). `false` keeps the paper's uniform draws.",
        },
        min_diversity: f64 = [value 0.8] {
            flag: Some(Flag::value("--min-diversity", "D")),
            range: Some(Limit::within(0.0, 1.0, "")),
            help: "Floor of the failing tests' diversity (1 - mean pairwise IoU): the adapted generator draws and \
                   flies only candidates that keep the expected final diversity above it.",
        },
        child_max_iou: f64 = [value 0.85] {
            flag: Some(Flag::value("--child-max-iou", "IOU")),
            range: Some(Limit::within(0.0, 1.0, "")),
            help: "A candidate drawn next to a failing flight may overlap a flown test up to this IoU (more than \
                   `max_iou`) while the failing tests would keep `min_diversity`: near copies of a failure fail \
                   most often. Set it to `max_iou` to hold every candidate to `max_iou`.",
        },
    }
}
