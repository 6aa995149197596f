//! The campaign TOML's keys as docs/cli.md documents them (example, default, the flag that overrides each), and
//! an example file with every key; tests check that every documented key parses and every key is documented.

use super::settings::SECTIONS;

/// One key of the campaign TOML, for docs/cli.md.
pub struct KeyDoc {
    pub section: &'static str,
    pub key: &'static str,
    /// A valid TOML value (the default where it is a constant).
    pub example: &'static str,
    pub default: &'static str,
    /// The `generate` flag that overrides it (empty: none).
    pub flag: &'static str,
    pub help: &'static str,
}

const fn key(
    section: &'static str,
    key: &'static str,
    example: &'static str,
    default: &'static str,
    flag: &'static str,
    help: &'static str,
) -> KeyDoc {
    KeyDoc {
        section,
        key,
        example,
        default,
        flag,
        help,
    }
}

/// Every key, in file order. A test parses them all, so a key documented here exists in the file format, and
/// every key of the format is documented here.
pub const KEYS: &[KeyDoc] = &[
    key(
        "generator",
        "diagonal_m",
        "{ min = 6.0, max = 11.6 }",
        "{ min = 6.0, max = 11.6 }",
        "--diagonal",
        "Diagonal of obstacle 1's base, metres; the upper bound keeps obstacle 2 (1.75 x as long) within the 20 m rule.",
    ),
    key("generator", "width_m", "2.0", "2.0", "", "Width of both bases, metres."),
    key(
        "generator",
        "split",
        "0.3333333333333333",
        "1/3",
        "",
        "Share of obstacle 1's length on the A side of the segment of interest (the paper family's).",
    ),
    key(
        "generator",
        "length_factor",
        "1.75",
        "1.75",
        "",
        "Obstacle 2's length as a multiple of obstacle 1's, so the drone cannot circle it.",
    ),
    key(
        "generator",
        "height_m",
        "20.0",
        "20.0",
        "--height",
        "Height of both boxes, metres (above the 10 m flight altitude, so the drone cannot fly over).",
    ),
    key(
        "generator",
        "angle_deg",
        "{ min = 20.0, max = 70.0 }",
        "{ min = 20.0, max = 70.0 }",
        "--angle",
        "Acute angle between obstacle 1's A part and the direction of flight, degrees.",
    ),
    key(
        "generator",
        "gap_m",
        "{ min = 2.0, max = 4.0 }",
        "{ min = 2.0, max = 4.0 }",
        "--gap",
        "Gap between obstacle 1's A end and obstacle 2, metres.",
    ),
    key(
        "generator",
        "overhang",
        "{ min = 0.0, max = 0.3333333333333333 }",
        "{ min = 0.0, max = 1/3 }",
        "",
        "How far obstacle 2 reaches past obstacle 1's far face, as a share of its length.",
    ),
    key(
        "generator",
        "family",
        "\"paper\"",
        "\"paper\"",
        "--family",
        "`paper` (two obstacles, the paper's split) or `extended` (the split drawn from `adapted_split`, and a \
         third obstacle beyond the pair where the mission leaves room).",
    ),
    key(
        "generator",
        "adapted_split",
        "{ min = 0.2, max = 0.45 }",
        "{ min = 0.2, max = 0.45 }",
        "",
        "The extended family's range of `split`.",
    ),
    key(
        "generator",
        "third_ahead_m",
        "{ min = 2.0, max = 8.0 }",
        "{ min = 2.0, max = 8.0 }",
        "",
        "The extended family's clear distance along the segment of interest from the pair to the third obstacle, \
         metres.",
    ),
    key(
        "generator",
        "max_attempts",
        "10000",
        "10000",
        "",
        "Draws per test before the generator reports that the mission leaves no room.",
    ),
    key(
        "output",
        "spelling",
        "\"new\"",
        "\"new\"",
        "--spelling",
        "Key spelling of the written YAML: `new` (robot/mission) or `old` (drone/test, Aerialist before 2025-09).",
    ),
    key(
        "screening",
        "candidates",
        "60",
        "3 x BUDGET, at least 20",
        "--candidates",
        "Candidates to draw and screen with the low-fidelity simulator.",
    ),
    key(
        "screening",
        "threshold_m",
        "3.0",
        "3.0",
        "--threshold",
        "Fly only candidates the simulator predicts closer than this, metres.",
    ),
    key(
        "screening",
        "max_iou",
        "0.5",
        "0.5",
        "--max-iou",
        "Skip a candidate whose footprints overlap an already chosen one by more than this IoU.",
    ),
    key(
        "screening",
        "motion",
        "\"px4\"",
        "\"px4\"",
        "--motion",
        "The simulator's motion model: `px4` or `paper`.",
    ),
    key(
        "screening",
        "ensemble",
        "0",
        "0 with mock vehicles, 8 with MAVLink ones",
        "--ensemble",
        "Members of the simulator ensemble run on the 2 x BUDGET most severe candidates, which are then flown in \
         order of expected points per minute; 0 ranks by the point prediction. An ensemble costs about 1 s of CPU \
         per candidate: more than a mock flight, far less than a PX4 or hardware flight.",
    ),
    key(
        "screening",
        "screen",
        "true",
        "true",
        "--no-screen",
        "`false` skips the simulator and flies candidates in the order drawn (the baseline that shows what \
         screening buys); it also turns learning off.",
    ),
    key(
        "mock",
        "speed",
        "100.0",
        "100.0",
        "--mock-speed",
        "Clock speed of the embedded mock autopilots, times real time; in lockstep an upper bound.",
    ),
    key(
        "mock",
        "lockstep",
        "true",
        "true",
        "--mock-free-running",
        "The mock holds its clock until each avoidance answer, so flights do not depend on the CPU. `false` lets \
         the clocks run free, as on a real vehicle (use a low speed, e.g. 20, with it).",
    ),
    key(
        "mock",
        "latency_ms",
        "0.0",
        "0.0",
        "--mock-latency",
        "In lockstep, the companion plans on the pose this many vehicle milliseconds old (0 to 1000).",
    ),
    key(
        "mock",
        "vehicles",
        "2",
        "one per core",
        "--mock-vehicles",
        "Embedded mock autopilots flying at once. Flights mostly wait on the mock's clock, so more vehicles than \
         cores can help while the planner keeps up. Not stored: a resumed campaign may change it.",
    ),
    key(
        "mock",
        "profile",
        "\"px4-sitl\"",
        "\"px4-sitl\"",
        "--mock-profile",
        "What the embedded mocks' avoidance flights are fitted to: `px4-sitl` (real PX4 v1.14 SITL) or \
         `competition` (the competition's recorded Gazebo flights); see docs/mock-autopilot.md.",
    ),
    key(
        "flight",
        "timeout_s",
        "500.0",
        "500.0",
        "--timeout",
        "Give a flight up (LAND) after this many vehicle seconds.",
    ),
    key(
        "flight",
        "connect_timeout_s",
        "15.0",
        "15.0",
        "--connect-timeout",
        "Seconds to wait for each MAVLink vehicle's first heartbeat. Not stored: a resumed campaign may change it.",
    ),
    key(
        "flight",
        "connect_time_scale",
        "1.0",
        "measured on each vehicle as it connects",
        "--connect-time-scale",
        "Clock rate of the `--connect` vehicles (PX4_SIM_SPEED_FACTOR).",
    ),
    key(
        "flight",
        "anchor_at_vehicle_home",
        "false",
        "false",
        "--anchor-at-vehicle-home",
        "Re-anchor every test (mission, obstacles, fence) at each vehicle's home instead of refusing a vehicle \
         farther from the test's home than its MIS_DIST_1WP (bench drones anywhere).",
    ),
    key(
        "flight",
        "confirm",
        "3",
        "3; 1 on the embedded mock without gusts (the `competition` profile, or outside avoidance mode)",
        "--confirm",
        "Flights a failing test gets at most (K, at least 1). A test whose flight fails is flown again, before \
         any new candidate and within the budget, until the majority of K flights is settled (K = 3: two \
         failures or two passes). Only a test more than half of whose flights fail is written as `test_N.yaml`; \
         the others that failed go to `unconfirmed.json`. 1 flies every test once.",
    ),
    key(
        "flight",
        "overlap",
        "false",
        "true with --connect, --px4 and --runner vehicles, false with the embedded mock",
        "",
        "Plan each learning round (draw, screen, ensemble, rank) while the previous one flies, so the vehicles \
         do not wait on the simulator; each round then learns from the flights before the previous round (one \
         round of lag). The embedded mock flies on the same cores as the screening, so it gains nothing there.",
    ),
    key(
        "learning",
        "learn",
        "true",
        "true",
        "--no-learn",
        "Fly in rounds (8, up to 12 while near-duplicates leave budget unflown), calibrating the simulator on \
         every flight. `false`: screen once and fly the ranking (the static campaign).",
    ),
    key(
        "learning",
        "adapt",
        "true",
        "true",
        "--no-adapt",
        "While learning, also adapt the generator towards failures (draws around failing flights, a draw \
         distribution moved towards the best candidates). `false` keeps the paper's uniform draws.",
    ),
    key(
        "learning",
        "min_diversity",
        "0.8",
        "0.8",
        "--min-diversity",
        "Floor of the failing tests' diversity (1 - mean pairwise IoU): the adapted generator draws and flies \
         only candidates that keep the expected final diversity above it (0 to 1).",
    ),
    key(
        "learning",
        "child_max_iou",
        "0.85",
        "0.85",
        "--child-max-iou",
        "A candidate drawn next to a failing flight may overlap a flown test up to this IoU (more than \
         `max_iou`) while the failing tests would keep `min_diversity`: near copies of a failure fail most \
         often. Set it to `max_iou` to hold every candidate to `max_iou`.",
    ),
];

/// The documented keys as a TOML file, each set to its example value.
pub fn example_toml() -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    for section in SECTIONS {
        let _ = writeln!(s, "[{section}]");
        for k in KEYS.iter().filter(|k| k.section == section) {
            let _ = writeln!(s, "{} = {}", k.key, k.example);
        }
    }
    s
}
