use proptest::prelude::*;

use super::*;

const T: Duration = Duration::from_secs(10);

fn message(frame: MavFrame, increment: u8, increment_f: f32, angle_offset: f32) -> OBSTACLE_DISTANCE_DATA {
    OBSTACLE_DISTANCE_DATA {
        time_usec: 0,
        distances: [UNKNOWN; BIN_COUNT],
        min_distance: 20,
        max_distance: 1000,
        sensor_type: MavDistanceSensor::MAV_DISTANCE_SENSOR_LASER,
        increment,
        increment_f,
        angle_offset,
        frame,
    }
}

fn ingest(m: &OBSTACLE_DISTANCE_DATA, yaw_deg: f64) -> ObstacleMap {
    let mut map = ObstacleMap::default();
    map.ingest(m, T, yaw_deg.to_radians(), T).expect("supported frame");
    map
}

/// Angular distance of two directions, degrees in [0, 180].
fn apart(a: f32, b: f32) -> f32 {
    let d = wrap_360(a - b);
    d.min(360.0 - d)
}

#[test]
fn aligned_body_sectors_land_in_one_bin_each() {
    let mut m = message(MavFrame::MAV_FRAME_BODY_FRD, 5, 0.0, 10.0);
    m.distances[0] = 300;
    m.distances[71] = 400;
    let map = ingest(&m, 123.0);
    assert_eq!(map.distances[2], 300);
    assert_eq!(map.distances[1], 400);
    assert_eq!(map.distances.iter().filter(|&&d| d != UNKNOWN).count(), 2);
    assert!(map.covered[1] && map.covered[2] && !map.covered[3]);
    assert_eq!((map.min_distance, map.max_distance, map.stamp), (20, 1000, T));
}

#[test]
fn north_aligned_sectors_turn_with_the_heading() {
    // An obstacle due East (90 degrees) seen while heading East is straight ahead.
    let mut m = message(MavFrame::MAV_FRAME_LOCAL_NED, 0, 10.0, 0.0);
    m.distances[9] = 250;
    let map = ingest(&m, 90.0);
    assert_eq!(map.distances[0], 250);
    // Heading North, the same obstacle is at 90 degrees, bins 17..=19 (a 10-degree sector spans three).
    let map = ingest(&m, 0.0);
    let known: Vec<usize> = (0..BIN_COUNT).filter(|&i| map.distances[i] != UNKNOWN).collect();
    assert_eq!(known, vec![17, 18, 19]);
    // MAV_FRAME_GLOBAL (0, the message's default) is North-aligned too.
    m.frame = MavFrame::MAV_FRAME_GLOBAL;
    assert_eq!(ingest(&m, 0.0).distances[18], 250);
}

#[test]
#[expect(deprecated, reason = "a sender may still use MAV_FRAME_BODY_NED")]
fn stale_zero_width_and_unsupported_messages_change_nothing() {
    let mut m = message(MavFrame::MAV_FRAME_BODY_FRD, 0, 0.0, 0.0);
    m.distances = [100; BIN_COUNT];
    assert_eq!(ingest(&m, 0.0), ObstacleMap::default());
    m.increment = 5;
    let mut map = ObstacleMap::default();
    map.ingest(&m, T, 0.0, T + RANGE_TIMEOUT).unwrap();
    assert_eq!(map, ObstacleMap::default());
    m.frame = MavFrame::MAV_FRAME_BODY_NED;
    let err = map.ingest(&m, T, 0.0, T).unwrap_err();
    assert!(err.contains("unsupported frame 8"), "{err}");
    assert_eq!(map, ObstacleMap::default());
}

#[test]
fn a_shorter_range_sensor_wins_and_out_of_range_does_not_erase_it() {
    let mut near = message(MavFrame::MAV_FRAME_BODY_FRD, 5, 0.0, 0.0);
    near.max_distance = 500;
    near.distances[0] = 300;
    let mut far = near.clone();
    far.max_distance = 2000;
    far.distances[0] = 900;
    let mut map = ObstacleMap::default();
    map.ingest(&near, T, 0.0, T).unwrap();
    map.ingest(&far, T, 0.0, T).unwrap();
    assert_eq!(map.distances[0], 300);
    // The near sensor now sees nothing in range: it may clear its own bin.
    near.distances[0] = 501;
    map.ingest(&near, T, 0.0, T).unwrap();
    assert_eq!(map.distances[0], 501);
    map.drop_stale(T + RANGE_TIMEOUT);
    assert_eq!(map.distances[0], 501);
    map.drop_stale(T + RANGE_TIMEOUT + Duration::from_millis(1));
    assert_eq!(map.distances[0], UNKNOWN);
    assert!(map.covered[0]);
}

#[test]
fn the_echo_is_the_body_frame_map() {
    let mut m = message(MavFrame::MAV_FRAME_BODY_FRD, 5, 0.0, 0.0);
    m.distances[3] = 700;
    let e = ingest(&m, 0.0).to_message(42);
    assert_eq!(
        (e.frame, e.increment, e.increment_f, e.distances[3]),
        (MavFrame::MAV_FRAME_BODY_FRD, 0, 5.0, 700)
    );
}

#[expect(deprecated, reason = "a sender may still use MAV_FRAME_BODY_NED")]
fn frames() -> impl Strategy<Value = MavFrame> {
    prop_oneof![
        Just(MavFrame::MAV_FRAME_GLOBAL),
        Just(MavFrame::MAV_FRAME_LOCAL_NED),
        Just(MavFrame::MAV_FRAME_BODY_FRD),
        Just(MavFrame::MAV_FRAME_BODY_NED),
        Just(MavFrame::MAV_FRAME_LOCAL_ENU),
    ]
}

fn floats() -> impl Strategy<Value = f32> {
    prop_oneof![
        any::<f32>(),
        -720.0f32..720.0,
        Just(0.0),
        Just(5.0),
        Just(f32::NAN),
        Just(f32::INFINITY)
    ]
}

proptest! {
    /// Any message is taken in without a panic, and every known bin holds a distance of the message.
    #[test]
    fn any_message_is_safe(
        distances in proptest::collection::vec(any::<u16>(), BIN_COUNT),
        min in any::<u16>(), max in any::<u16>(), inc in any::<u8>(), inc_f in floats(),
        offset in floats(), frame in frames(), yaw in -10.0f64..10.0,
    ) {
        let mut m = message(frame, inc, inc_f, offset);
        m.distances.copy_from_slice(&distances);
        (m.min_distance, m.max_distance) = (min, max);
        let mut map = ObstacleMap::default();
        let _ = map.ingest(&m, T, yaw, T);
        for d in map.distances {
            prop_assert!(d == UNKNOWN || m.distances.contains(&d));
        }
        let _ = map.to_message(0);
    }

    /// On an empty map, a body-frame message puts a known sector's distance only into bins the sector reaches
    /// (widths that divide 360: otherwise PX4 numbers sectors modulo the whole ones, so the last sector lies over
    /// sector 0 and the one before stretches to meet it, ObstacleMath `get_lower_bound_angle`). With 5-degree
    /// sectors on the bins' grid the mapping is one to one. (Off the grid PX4 misses bins just left of North
    /// for a sector that straddles it: its overlap test compares a wrapped sector with an unwrapped bin.)
    #[test]
    fn body_sectors_map_by_angle(
        known in proptest::collection::vec(proptest::option::of(1u16..5000), BIN_COUNT),
        inc in proptest::sample::select(vec![3.0f32, 4.0, 5.0, 6.0, 7.5, 8.0, 9.0, 10.0, 12.0, 15.0, 22.5, 30.0, 45.0, 90.0]),
        offset in prop_oneof![(-72i32..72).prop_map(|k| k as f32 * 5.0), -360.0f32..360.0],
    ) {
        let mut m = message(MavFrame::MAV_FRAME_BODY_FRD, 0, inc, offset);
        for (j, d) in known.iter().enumerate() {
            m.distances[j] = d.unwrap_or(UNKNOWN);
        }
        let map = ingest(&m, 0.0);
        let sectors = (0..BIN_COUNT).filter(|&j| (j as f32) < 360.0 / inc);
        let centre = |j: usize| j as f32 * inc + offset;
        for i in 0..BIN_COUNT {
            let d = map.distances[i];
            let reach = inc / 2.0 + BIN_DEG / 2.0 + 1e-2;
            prop_assert!(d == UNKNOWN
                || sectors.clone().any(|j| m.distances[j] == d && apart(centre(j), i as f32 * BIN_DEG) <= reach),
                "bin {i} = {d}");
        }
        if inc == 5.0 && offset.fract() == 0.0 && offset as i32 % 5 == 0 {
            let shift = (offset as i64 / 5).rem_euclid(BIN_COUNT as i64) as usize;
            for j in 0..BIN_COUNT {
                prop_assert_eq!(map.distances[(j + shift) % BIN_COUNT], m.distances[j]);
            }
        }
    }
}
