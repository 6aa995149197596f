use proptest::prelude::*;

use super::*;

fn wall_north() -> SensorScene {
    // A 2 m x 10 m box whose south face is 5 m north of the origin.
    SensorScene::new(&[Obstacle::new(2.0, 10.0, 20.0, 6.0, 0.0, 0.0)])
}

#[test]
fn the_sector_ahead_sees_the_face_and_the_rear_is_free() {
    let s = RangeSensor::default();
    let scan = s.scan(&wall_north(), [0.0, 0.0, -5.0], 0.0);
    // Sector 0 spans -2.5..2.5 degrees; its closest ray is the one nearest the nose.
    assert!((i32::from(scan[0]) - 500).abs() <= 1, "{}", scan[0]);
    assert_eq!(scan[36], s.max_cm + 1, "behind: nothing within range");
    assert_eq!(s.closest_m(&scan), Some(f64::from(scan[0]) / 100.0));
}

#[test]
fn sectors_are_in_the_body_frame() {
    let s = RangeSensor::default();
    // Nose east (yaw 90 degrees): the northern wall is on the left, sector 270 degrees = 54.
    let scan = s.scan(&wall_north(), [0.0, 0.0, -5.0], std::f64::consts::FRAC_PI_2);
    assert!((i32::from(scan[54]) - 500).abs() <= 1, "{}", scan[54]);
    assert_eq!(scan[0], s.max_cm + 1);
}

#[test]
fn above_the_box_nothing_is_seen() {
    let s = RangeSensor::default();
    let scan = s.scan(&wall_north(), [0.0, 0.0, -25.0], 0.0);
    assert!(scan.iter().all(|d| *d == s.max_cm + 1));
    assert_eq!(s.closest_m(&scan), None);
}

#[test]
fn inside_or_touching_a_box_reads_the_minimum() {
    let s = RangeSensor::default();
    let scan = s.scan(&wall_north(), [6.0, 0.0, -5.0], 0.0);
    assert!(scan.iter().all(|d| *d == s.min_cm), "{scan:?}");
}

proptest! {
    /// No sector reads closer than the true distance to the box (within a centimetre of rounding), and the
    /// closest sector is near it (rays a degree apart can pass beside a corner and meet a face behind it).
    #[test]
    fn sectors_never_read_closer_than_the_box(x in -20.0..20.0f64, y in -20.0..20.0f64, yaw in -3.2..3.2f64) {
        let o = Obstacle::new(4.0, 3.0, 20.0, 0.0, 0.0, 30.0);
        let truth = crate::geometry::point_box_distance(&o.solid(), [x, y, 5.0]);
        prop_assume!(truth > 0.3 && truth < 11.0);
        let s = RangeSensor::default();
        let scan = s.scan(&SensorScene::new(&[o]), [x, y, -5.0], yaw);
        let seen = s.closest_m(&scan).unwrap();
        prop_assert!(seen >= truth - 0.011, "seen {seen} truth {truth}");
        prop_assert!(seen <= truth + 1.0, "seen {seen} truth {truth}");
    }
}
