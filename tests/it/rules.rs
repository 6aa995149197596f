//! Every rule of docs/formats.md, "Rules for a valid test", each broken on its own.

use prgenuav::model::{Arena, Obstacle};
use prgenuav::rules::check_obstacles;

use super::{case, prgenuav, test_file, valid_pair};

fn violations(obstacles: Vec<Obstacle>) -> Vec<String> {
    let m = case(2).mission;
    check_obstacles(&obstacles, &m, &Arena::default())
        .into_iter()
        .map(|v| format!("{} | {}", v.path, v.rule))
        .collect()
}

fn only(obstacles: Vec<Obstacle>, path: &str, rule_part: &str) {
    let v = violations(obstacles);
    assert_eq!(v.len(), 1, "expected exactly one violation, got {v:#?}");
    assert!(v[0].starts_with(path) && v[0].contains(rule_part), "{v:#?}");
}

#[test]
fn a_valid_test_passes() {
    assert!(violations(valid_pair()).is_empty(), "{:#?}", violations(valid_pair()));
    let (_d, path) = test_file(2, valid_pair());
    let (code, out, err) = prgenuav(&["check", path.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("\"valid\": true"));
}

#[test]
fn each_rule_is_detected_on_its_own() {
    let base = || Obstacle::new(6.0, 3.0, 20.0, -20.0, 25.0, 10.0);
    let with = |f: &dyn Fn(&mut Obstacle)| {
        let mut o = base();
        f(&mut o);
        vec![o]
    };
    assert!(violations(vec![base()]).is_empty());
    only(with(&|o| o.size.l = 21.0), "simulation.obstacles[0].size.l", "length");
    only(with(&|o| o.size.l = 1.5), "simulation.obstacles[0].size.l", "length");
    only(with(&|o| o.size.w = 1.0), "simulation.obstacles[0].size.w", "width");
    only(
        with(&|o| o.size.h = 26.0),
        "simulation.obstacles[0].size.h",
        "height must be in",
    );
    only(
        with(&|o| o.position.r = 91.0),
        "simulation.obstacles[0].position.r",
        "rotation",
    );
    only(
        with(&|o| o.position.r = -1.0),
        "simulation.obstacles[0].position.r",
        "rotation",
    );
    only(
        with(&|o| o.position.z = 1.0),
        "simulation.obstacles[0].position.z",
        "ground",
    );
    // Centre inside, footprint outside.
    only(
        with(&|o| o.position.y = 11.0),
        "simulation.obstacles[0].position",
        "whole footprint",
    );
    only(
        with(&|o| o.position.x = 28.0),
        "simulation.obstacles[0].position",
        "whole footprint",
    );
    // Centre outside the x range (and so the footprint too).
    let v = violations(with(&|o| o.position.x = 35.0));
    assert!(
        v.iter().any(|s| s.contains("position.x")) && v.iter().any(|s| s.contains("whole footprint")),
        "{v:#?}"
    );
}

#[test]
fn height_must_exceed_the_flight_altitude() {
    // 10 m is in the 10..25 range but not above the 10 m flight altitude.
    only(
        vec![Obstacle::new(6.0, 3.0, 10.0, -20.0, 25.0, 10.0)],
        "simulation.obstacles[0].size.h",
        "exceed",
    );
}

#[test]
fn too_many_obstacles() {
    let o: Vec<Obstacle> = (0..4)
        .map(|i| Obstacle::new(3.0, 3.0, 20.0, -35.0 + 9.0 * i as f64, 25.0, 0.0))
        .collect();
    only(o, "simulation.obstacles", "at most 3");
}

#[test]
fn overlap_and_touch_are_detected() {
    let a = Obstacle::new(4.0, 4.0, 20.0, -20.0, 25.0, 0.0);
    only(
        vec![a, Obstacle::new(4.0, 4.0, 20.0, -17.0, 25.0, 0.0)],
        "simulation.obstacles[1]",
        "overlap",
    );
    only(
        vec![a, Obstacle::new(4.0, 4.0, 20.0, -16.0, 25.0, 0.0)],
        "simulation.obstacles[1]",
        "touch",
    );
    assert!(violations(vec![a, Obstacle::new(4.0, 4.0, 20.0, -15.0, 25.0, 0.0)]).is_empty());
}

#[test]
fn a_wall_across_the_arena_is_infeasible() {
    // Diamonds corner to corner with 1 m gaps, from 1 m off the left border to 2 m off the right one.
    let wall = vec![
        Obstacle::new(20.0, 20.0, 20.0, -24.86, 25.0, 45.0),
        Obstacle::new(20.0, 20.0, 20.0, 4.42, 25.0, 45.0),
        Obstacle::new(6.0, 6.0, 20.0, 23.8, 25.0, 45.0),
    ];
    only(wall, "simulation.obstacles", "wall off");
}

#[test]
fn a_box_on_a_waypoint_is_infeasible() {
    // Every public waypoint lies outside the arena, so widen the arena to hold mission 2's far waypoint.
    let m = case(2).mission;
    let wp = m.flight_path()[1];
    let o = Obstacle::new(4.0, 4.0, 20.0, wp.north_m, wp.east_m, 0.0);
    let v = check_obstacles(
        &[o],
        &m,
        &Arena {
            y: prgenuav::model::Range::new(10.0, 60.0),
            ..Arena::default()
        },
    );
    assert!(v.iter().any(|v| v.rule.contains("waypoint 1")), "{v:#?}");
}

#[test]
fn check_cli_exit_codes_and_json() {
    let mut bad = valid_pair();
    bad[0].size.l = 30.0;
    let (_d, path) = test_file(2, bad);
    let (code, out, _) = prgenuav(&["check", path.to_str().unwrap(), "--json"]);
    assert_eq!(code, 1);
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(json["valid"], false);
    assert_eq!(json["violations"][0]["path"], "simulation.obstacles[0].size.l");
    assert_eq!(json["violations"][0]["value"], 30.0);
    for n in 1..=7 {
        let (code, out, err) = prgenuav(&["check", &format!("missions/mission{n}.yaml")]);
        assert_eq!(code, 0, "mission{n}: {out}{err}");
    }
}
