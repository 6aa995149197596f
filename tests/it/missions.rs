//! The public missions: projection of their waypoints, and YAML round trips.

use prgenuav::model::{CMD_LAND, Spelling, TestCase};

use super::{case, repo, valid_pair};

fn land(n: u32) -> (f64, f64) {
    let m = case(n).mission;
    let item = m.items.iter().find(|i| i.command == CMD_LAND).expect("a land item");
    let p = item.local.expect("land has a position");
    (p.north_m, p.east_m)
}

#[test]
fn missions_land_within_5_cm_of_the_published_coordinates() {
    // The published coordinates: docs/formats.md, "Frames".
    let expected = [
        (1, (3.30, 53.09)),
        (2, (-12.36, 0.13)),
        (3, (-17.87, 0.99)),
        (4, (-20.05, 54.08)),
        (5, (30.04, 54.08)),
        (6, (-5.02, -0.02)),
        (7, (-18.04, -0.02)),
    ];
    for (n, (x, y)) in expected {
        let (nx, ny) = land(n);
        let err = (nx - x).hypot(ny - y);
        assert!(
            err < 0.05,
            "mission{n}: land at ({nx:.3}, {ny:.3}), expected ({x}, {y}), {err:.3} m off"
        );
    }
}

#[test]
fn mission_waypoints_match_the_published_coordinates() {
    let m2 = case(2).mission.flight_path();
    assert_eq!(m2.len(), 3, "takeoff, waypoint, land");
    assert!((m2[1].north_m + 6.84).abs() < 0.05 && (m2[1].east_m - 53.97).abs() < 0.05);
    assert!((m2[1].alt_m - 10.0).abs() < 1e-9);
    let m3 = case(3).mission.flight_path();
    assert!((m3[2].north_m + 14.71).abs() < 0.05 && (m3[2].east_m - 54.11).abs() < 0.05);
    // The camera item (530) is kept but not flown.
    assert!(
        case(2)
            .mission
            .items
            .iter()
            .any(|i| i.command == 530 && i.local.is_none())
    );
}

#[test]
fn yaml_read_write_read_gives_equal_values() {
    let original = case(2).with_obstacles(valid_pair());
    for spelling in [Spelling::Old, Spelling::New] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.yaml");
        original.save(&path, spelling).unwrap();
        let back = TestCase::load(&path).unwrap();
        assert_eq!(back.obstacles, original.obstacles);
        assert_eq!(back.params, original.params);
        assert_eq!(back.commands, original.commands);
        assert_eq!(back.mission.items, original.mission.items);
        assert_eq!(back.spelling, spelling);
        // Written again, the file is byte-identical.
        assert_eq!(back.to_yaml(spelling), original.to_yaml(spelling));
    }
}

#[test]
fn blocks_we_do_not_interpret_are_kept() {
    let text = std::fs::read_to_string(repo().join("missions/mission1.yaml")).unwrap()
        + "assertion:\n  log_file: samples/flights/mission1.ulg\n  variable: trajectory\nagent:\n  engine: local\n  count: 3\n";
    let (_d, path) = super::temp_file("c.yaml", text.as_bytes());
    let t = TestCase::load(&path).unwrap();
    let out = t.to_yaml(Spelling::New);
    assert!(
        out.contains("robot:") && out.contains("mission:") && !out.contains("drone:"),
        "{out}"
    );
    assert!(
        out.contains("log_file: samples/flights/mission1.ulg") && out.contains("engine: local"),
        "{out}"
    );
}

#[test]
fn inline_params_and_commands_are_read() {
    let yaml = "robot:\n  params:\n    NAV_ACC_RAD: 0.5\n    MPC_XY_CRUISE: 3\n  mission_file: missions/mission1.plan\n\
                mission:\n  commands:\n  - {timestamp: 1, mode: 3, x: 0, y: 0, z: 0.5, r: 0}\n";
    let t = TestCase::parse(yaml, &repo().join("inline.yaml")).unwrap();
    assert_eq!(t.params.len(), 2);
    assert_eq!(t.params[1].name, "MPC_XY_CRUISE");
    assert_eq!(t.commands[0].mode, 3);
    assert_eq!(t.spelling, Spelling::New);
}
