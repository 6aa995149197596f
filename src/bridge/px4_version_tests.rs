use super::*;
use proptest::prelude::*;

fn v(text: &str) -> Px4Version {
    Px4Version::parse(text).unwrap_or_else(|| panic!("{text} parses"))
}

#[test]
fn tags_of_releases_forks_and_candidates_parse() {
    let fork = v("v1.14.0-beta2-325-g1555f2bd22");
    assert_eq!((fork.major, fork.minor, fork.patch), (1, 14, 0));
    assert_eq!(fork.to_string(), "v1.14.0-beta2-325-g1555f2bd22");
    assert_eq!((v("v1.16.2").minor, v("v1.16.2").patch), (16, 2));
    assert_eq!(v("1.17.0-rc1").minor, 17);
    for bad in ["", "main", "v1", "v1.16", "vX.16.2", "v1.x.2", "1.16.a"] {
        assert_eq!(Px4Version::parse(bad), None, "{bad:?}");
    }
}

#[test]
fn autopilot_version_reads_major_minor_patch() {
    let got = Px4Version::from_flight_sw(0x0110_02FF).unwrap();
    assert_eq!(
        (got.major, got.minor, got.patch, got.text.as_str()),
        (1, 16, 2, "1.16.2")
    );
    assert_eq!(Px4Version::from_flight_sw(0x010E_0080).unwrap().minor, 14);
    assert_eq!(Px4Version::from_flight_sw(0), None);
}

#[test]
fn the_table_splits_at_v1_16() {
    for (tag, avoid, home) in [
        ("v1.14.0", true, HomeUnits::IntE7),
        ("v1.15.4", true, HomeUnits::IntE7),
        ("v1.16.2", false, HomeUnits::FloatDegrees),
        ("v1.17.0", false, HomeUnits::FloatDegrees),
    ] {
        let r = v(tag).release().unwrap();
        assert_eq!((r.avoidance_interface, r.sih), (avoid, Some(home)), "{tag}");
        assert_eq!((r.external.model, r.external.startup), ("none_iris", None), "{tag}");
        assert!(r.collision_prevention, "{tag}");
        assert_eq!(r.supports(FlyMode::Avoidance), avoid, "{tag}");
        assert!(r.supports(FlyMode::Offboard) && r.supports(FlyMode::Mission), "{tag}");
        assert!(r.supports(FlyMode::CollisionPrevention), "{tag}");
    }
    assert_eq!(
        v("v1.14.0").release().unwrap().modes(),
        "avoidance, offboard, mission, collision-prevention"
    );
    assert_eq!(
        v("v1.16.2").release().unwrap().modes(),
        "offboard, mission, collision-prevention"
    );
}

#[test]
fn an_unchecked_release_is_refused_by_name() {
    let err = v("v1.18.0-beta1").release().unwrap_err().to_string();
    assert!(err.contains("PX4 v1.18.0-beta1 (read as 1.18)"), "{err}");
    assert!(err.contains("checked: 1.12, 1.14, 1.15, 1.16, 1.17"), "{err}");
    assert!(v("v1.13.3").release().is_err());
    assert!(v("v2.14.0").release().is_err());
}

#[test]
fn v1_12_flies_only_with_an_external_simulator() {
    let version = v("v1.12.3-dirty");
    let r = version.release().unwrap();
    assert_eq!(r.sih, None);
    assert_eq!(
        (r.external.model, r.external.startup, r.external.module),
        ("iris", Some("etc/init.d-posix/rcS"), "px4-simulator")
    );
    assert_eq!((r.checked, r.checked_iris), (Checked::Absent, Checked::Flown));
    let refused = r.sim_refusal(&version, VehicleSim::Sih).expect("no SIH in v1.12");
    assert!(
        refused.starts_with("--sim sih: PX4 v1.12.3-dirty has no SIH in SITL") && refused.ends_with("--sim iris"),
        "{refused}"
    );
    assert_eq!(r.sim_refusal(&version, VehicleSim::Iris), None);
    assert_eq!(r.modes(), "avoidance, offboard, mission, collision-prevention");
    let v114 = v("v1.14.0");
    assert_eq!(v114.release().unwrap().sim_refusal(&v114, VehicleSim::Sih), None);
}

#[test]
fn the_avoidance_refusal_names_the_version_and_the_modes_that_work() {
    let version = v("v1.16.2");
    let msg = mode_refusal(&version, version.release().unwrap(), FlyMode::Avoidance);
    assert!(
        msg.starts_with("--mode avoidance: PX4 v1.16.2 has no obstacle-avoidance interface"),
        "{msg}"
    );
    assert!(
        msg.ends_with("modes that work on PX4 1.16: offboard, mission, collision-prevention"),
        "{msg}"
    );
}

proptest! {
    #[test]
    fn parse_never_panics_and_keeps_the_numbers(major in 0u32..1000, minor in 0u32..1000, patch in 0u32..1000, tail in "[-a-z0-9.]{0,12}") {
        let text = format!("v{major}.{minor}.{patch}{tail}");
        let got = Px4Version::parse(&text);
        // A tail starting with a digit extends the patch number.
        if !tail.starts_with(|c: char| c.is_ascii_digit()) {
            let got = got.expect("parses");
            prop_assert_eq!((got.major, got.minor, got.patch), (major, minor, patch));
        }
    }

    #[test]
    fn arbitrary_text_never_panics(text in ".{0,40}") {
        let _ = Px4Version::parse(&text);
    }
}
