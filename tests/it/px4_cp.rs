//! Collision Prevention on PX4 v1.16 (ignored by default; CI does not run it): one test of the gate family,
//! flown in `collision-prevention` mode on a fresh SIH instance of the v1.16.x build in `PX4_SITL_BIN_V116`,
//! lands and is judged; the closest the vehicle's centre came to a box is said on stderr.
//!
//! `PX4_SITL_BIN_V116=/path/to/v1.16/build/px4_sitl_default/bin/px4 cargo test -- --ignored px4_cp --nocapture`

use prgenuav::bridge::{FlyMode, Status};
use prgenuav::generator::{Family, Generator, GeneratorConfig};

use super::case;
use super::px4_release::release_bin;
use super::px4_sitl::{build_of, fly_on, start};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V116 (PX4 v1.16 SITL); run with --ignored px4_cp"]
async fn a_gate_test_in_collision_prevention_mode_lands_and_is_judged() {
    let bin = release_bin("PX4_SITL_BIN_V116", 16);
    let build = build_of(&bin);
    let c = case(2);
    let gate = GeneratorConfig {
        family: Family::Gate,
        ..GeneratorConfig::default()
    };
    let g = Generator::new(&c, gate, 0).expect("generator");
    let test = c.with_obstacles(g.sample(0).expect("sample").obstacles.to_vec());
    let px4 = start(&bin, 8);
    let what = format!("PX4 {} mission 2 gate test 0", build.version);
    let r = fly_on(&px4, &test, FlyMode::CollisionPrevention, &what).await;
    let console = px4.console_tail(40).join("\n");
    assert_eq!(r.status, Status::Landed, "{:?} {:?}\n{console}", r.reason, r.warnings);
    let flown = r.min_distance.expect("judged");
    let cp = r.collision_prevention.expect("a Collision Prevention verdict");
    let centre = cp.closest_centre_m.expect("the closest centre measured");
    eprintln!(
        "px4_cp: {what}: judged {flown:.2} m, closest centre {centre:.2} m, inside CP_DIST {} m: {:?}",
        cp.cp_dist_m, cp.inside_cp_dist
    );
    assert!(
        centre.is_finite() && centre >= 0.0 && centre <= flown + 1.0,
        "centre {centre}, judged {flown}"
    );
}
