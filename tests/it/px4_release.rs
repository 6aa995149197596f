//! What the per-release PX4 conformance tests share (`px4_v115.rs`, `px4_v116.rs`, `px4_v117.rs`, `px4_cp.rs`): the build from its own
//! environment variable, checked to be that release; a claimed instance slot, so a conformance run does not
//! take the ports of another flight on the machine; and a Collision Prevention flight of a mission's test.

use std::path::{Path, PathBuf};
use std::time::Instant;

use prgenuav::bridge::sitl::slot::{self, Slot};
use prgenuav::bridge::{FlyMode, Status};

use super::px4_sitl::{build_of, fly_on, generated, start};

/// The build in `var` (`BUILD/bin/px4`), checked to be PX4 1.`minor`. Unset, the test fails naming `var`.
pub(super) fn release_bin(var: &str, minor: u32) -> PathBuf {
    let bin = match std::env::var_os(var) {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => panic!(
            "this test flies PX4 v1.{minor} SITL: set {var}=/path/to/PX4-Autopilot-v1.{minor}/build/\
             px4_sitl_default/bin/px4 (a PX4 v1.{minor}.x SITL you built; docs/px4-versions.md)"
        ),
    };
    let build = build_of(&bin);
    assert_eq!(
        (build.release.major, build.release.minor),
        (1, minor),
        "{var}={}: PX4 {}, not v1.{minor}",
        bin.display(),
        build.version
    );
    bin
}

/// A free instance slot of this machine, held while the test flies.
pub(super) fn claimed() -> Slot {
    slot::claim(0).unwrap_or_else(|e| panic!("{e}"))
}

/// Mission `mission`'s conformance test flown in `collision-prevention` mode on a fresh instance: the pilot
/// lands, or gives up behind a box as a timeout saying so; either way the vehicle ends on the ground and the
/// flight is judged, with the closest the vehicle's centre came to a box. One `px4_cp:` line goes to stderr.
pub(super) async fn collision_prevention(bin: &Path, mission: u32) {
    let build = build_of(bin);
    let slot = claimed();
    let test = generated(mission, 0);
    let px4 = start(bin, slot.instance());
    let what = format!("PX4 {} mission {mission}", build.version);
    let wall = Instant::now();
    let r = fly_on(&px4, &test, FlyMode::CollisionPrevention, &what).await;
    let wall_s = wall.elapsed().as_secs_f64();
    let console = px4.console_tail(40).join("\n");
    let why = r.reason.clone().unwrap_or_default();
    let cp = r
        .collision_prevention
        .unwrap_or_else(|| panic!("{what}: no Collision Prevention verdict: {why}"));
    eprintln!(
        "px4_cp: {what} | {} | judged {} m | closest centre {} m | CP_DIST {} m, inside {:?} | {:.0} s vehicle | \
         {wall_s:.0} s wall | {why}",
        r.status.as_str(),
        r.min_distance.map_or("-".into(), |d| format!("{d:.2}")),
        cp.closest_centre_m.map_or("-".into(), |d| format!("{d:.2}")),
        cp.cp_dist_m,
        cp.inside_cp_dist,
        r.flight_time_s,
    );
    match r.status {
        Status::Landed => {}
        Status::Timeout => assert!(why.contains("did not reach waypoint"), "{what}: {why}"),
        other => panic!("{what}: {} ({why}), {:?}\n{console}", other.as_str(), r.warnings),
    }
    assert!(r.min_distance.is_some(), "{what}: not judged");
    let centre = cp.closest_centre_m.expect("the closest centre measured");
    assert_eq!(cp.inside_cp_dist, Some(centre < cp.cp_dist_m), "{what}");
    let (first, last) = (r.trajectory.samples.first(), r.trajectory.samples.last());
    let (first, last) = (first.expect("positions"), last.expect("positions"));
    assert!(r.flight_time_s > 20.0, "{what}: flew {} s", r.flight_time_s);
    assert!(
        (last.z - first.z).abs() < 1.5,
        "{what}: ended at height {:.2} m, started at {:.2} m: not back on the ground\n{console}",
        last.z,
        first.z
    );
}
