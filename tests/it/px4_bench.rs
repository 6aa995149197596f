//! The competition bench on a real PX4 v1.12 build (ignored by default; CI does not run it): what it was not
//! checked on is flown, and the flight's report names it. Needs a PX4 v1.12.x SITL the user built:
//!
//! `PX4_SITL_BIN_V112=/path/to/v1.12.3/build/px4_sitl_default/bin/px4 cargo test --release --test it px4_bench --
//! --ignored --nocapture`

use std::path::Path;

use prgenuav::model::Obstacle;

use super::px4_release::release_bin;
use super::px4_sitl::generated;

#[test]
#[ignore = "needs PX4_SITL_BIN_V112 (PX4 v1.12 SITL); run with --ignored px4_bench"]
fn a_third_box_that_is_low_is_flown_on_the_competition_bench_and_named_in_the_report() {
    let bin = release_bin("PX4_SITL_BIN_V112", 12);
    let build = bin.parent().and_then(Path::parent).expect("BUILD/bin/px4");
    let mut obstacles = generated(1, 0).obstacles;
    // Far West of mission 1's leg (x 0 to 3.3 m North), 1 m above its 10 m flight.
    obstacles.push(Obstacle::new(2.0, 2.0, 11.0, -35.0, 12.0, 0.0));
    let (_dir, test) = super::test_file(1, obstacles);
    let b = build.to_str().expect("a UTF-8 path");
    let t = test.to_str().expect("a UTF-8 path");
    let (_, out, err) = super::prgenuav(&[
        "fly",
        t,
        "--px4",
        b,
        "--bench",
        "competition",
        "--json",
        "--timeout",
        "300",
    ]);
    let report: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}\n{err}"));
    assert_eq!(report["status"], "landed", "{err}");
    let warnings: Vec<&str> = report["warnings"]
        .as_array()
        .expect("warnings")
        .iter()
        .filter_map(|w| w.as_str())
        .collect();
    assert!(warnings.iter().any(|w| w.starts_with("3 obstacles")), "{warnings:?}");
    assert!(
        warnings
            .iter()
            .any(|w| w.starts_with("simulation.obstacles[2] is 11.0 m high")),
        "{warnings:?}"
    );
}
