use super::*;
use crate::campaign::store::journal::test_record;

#[test]
fn paths_leaving_the_folder_are_not_inside() {
    for p in ["flights/candidate_1.csv", "./flights/x.csv", ""] {
        assert!(is_inside(Path::new(p)), "{p}");
    }
    for p in ["../x.csv", "flights/../../etc/passwd", "/etc/passwd"] {
        assert!(!is_inside(Path::new(p)), "{p}");
    }
}

#[test]
fn distances_outside_the_arena_and_odd_times_are_refused() {
    let ok = test_record(1, 1.0, Some(2.0));
    check_record(&ok, 100.0).unwrap();
    for d in [-1.0, 1e300, 100.5] {
        let e = check_record(&test_record(1, 1.0, Some(d)), 100.0).unwrap_err();
        assert!(e.contains("min_distance") && e.contains("outside [0, 100.0]"), "{e}");
    }
    let mut slow = ok.clone();
    slow.flown.flight_time_s = -3.0;
    assert!(check_record(&slow, 100.0).unwrap_err().contains("flight_time_s"));
    let away = FlightRecord {
        trajectory: "../../../../etc/hosts".into(),
        ..ok
    };
    let e = check_record(&away, 100.0).unwrap_err();
    assert!(
        e.contains("../../../../etc/hosts") && e.contains("not a file inside"),
        "{e}"
    );
}

#[test]
fn a_link_inside_the_folder_is_not_read_through() {
    let dir = tempfile::tempdir().unwrap();
    let secret = dir.path().join("secret");
    std::fs::write(&secret, "s").unwrap();
    std::fs::create_dir(dir.path().join("f")).unwrap();
    std::os::unix::fs::symlink(&secret, dir.path().join("f/l.csv")).unwrap();
    std::fs::write(dir.path().join("f/r.csv"), "r").unwrap();
    assert_eq!(inside_bytes(dir.path(), Path::new("f/l.csv")), None);
    assert_eq!(inside_bytes(dir.path(), Path::new("f/r.csv")), Some(b"r".to_vec()));
    assert_eq!(inside_bytes(dir.path(), Path::new("f/../secret")), None);
    std::os::unix::fs::symlink(dir.path().join("f"), dir.path().join("g")).unwrap();
    assert_eq!(inside_bytes(dir.path(), Path::new("g/r.csv")), None, "a linked folder");
}

#[test]
fn a_link_or_a_file_in_a_folders_place_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let own = dir.path().join("flights");
    make_own_folder(&own, "the campaign").unwrap();
    make_own_folder(&own, "the campaign").unwrap();
    assert!(own.is_dir());
    check_own_folder(&dir.path().join("missing"), "the campaign").unwrap();
    let elsewhere = tempfile::tempdir().unwrap();
    let link = dir.path().join("averages");
    std::os::unix::fs::symlink(elsewhere.path(), &link).unwrap();
    let e = make_own_folder(&link, "evaluate").unwrap_err().to_string();
    assert!(
        e.contains("averages") && e.contains("a link to") && e.contains("evaluate writes only inside"),
        "{e}"
    );
    std::fs::write(dir.path().join("jobs"), "").unwrap();
    let e = check_own_folder(&dir.path().join("jobs"), "evaluate")
        .unwrap_err()
        .to_string();
    assert!(e.contains("it is a file"), "{e}");
    assert!(same_folder(&link, elsewhere.path()) && !same_folder(&own, elsewhere.path()));
}
