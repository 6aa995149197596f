use super::*;

const NORTH: f32 = std::f32::consts::FRAC_PI_2;

fn zero() -> Fov {
    Fov {
        yaw_deg: 0.0,
        pitch_deg: 0.0,
        h_fov_deg: 0.0,
        v_fov_deg: 0.0,
    }
}

fn level(x: f32, y: f32, z: f32, yaw_enu_rad: f32) -> BodyPose {
    BodyPose {
        position_enu: Vector3::new(x, y, z),
        yaw_enu_rad,
        pitch_rad: 0.0,
    }
}

#[test]
fn body_frame_undoes_yaw_and_nose_down_pitch() {
    // Facing North: a point 10 m North and 1 m West is ahead and to the left.
    let b = level(0.0, 0.0, 5.0, NORTH).body_flu(&Vector3::new(-1.0, 10.0, 5.0));
    assert!((b - Vector3::new(10.0, 1.0, 0.0)).norm() < 1e-5, "{b}");
    // Pitched 10 deg nose-down, the body's forward axis points 10 deg below the horizon.
    let pose = BodyPose {
        pitch_rad: 10f32.to_radians(),
        ..level(0.0, 0.0, 0.0, 0.0)
    };
    let (s, c) = 10f32.to_radians().sin_cos();
    let b = pose.body_flu(&Vector3::new(c, 0.0, -s));
    assert!((b - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-6, "{b}");
    // Optical: x right, y down, z forward.
    let o = optical_from_body(&Vector3::new(3.0, 1.0, 2.0));
    assert_eq!(o, Vector3::new(-1.0, -2.0, 3.0));
}

#[test]
fn maxima_take_the_first_of_equal_values_and_skip_nan() {
    let pts = [
        Vector3::new(f32::NAN, 9.0, 9.0),
        Vector3::new(1.0, 5.0, 2.0),
        Vector3::new(1.0, 5.0, 3.0),
        Vector3::new(-1.0, 0.0, 2.0),
    ];
    // x max, y max, z max, x min, y min, z min.
    assert_eq!(maxima_indices(&pts), vec![1, 1, 2, 3, 3, 1]);
    assert!(maxima_indices(&[Vector3::new(f32::NAN, 0.0, 0.0)]).is_empty());
}

#[test]
fn spread_signs_left_is_positive_azimuth_below_is_positive_elevation() {
    let mut f = zero();
    // Ahead; 45 deg left and level; 30 deg below the horizon straight ahead.
    let s3 = 3f32.sqrt();
    grow_from_maxima(
        &mut f,
        &[
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(s3, 0.0, -1.0),
        ],
    );
    assert!((f.h_fov_deg - 45.0).abs() < 1e-3, "{f:?}");
    assert!((f.yaw_deg - 22.5).abs() < 1e-3, "{f:?}");
    assert!((f.v_fov_deg - 30.0).abs() < 1e-3, "{f:?}");
    assert!((f.pitch_deg - 15.0).abs() < 1e-3, "{f:?}");
}

#[test]
fn estimate_only_grows_per_axis() {
    let mut f = zero();
    grow_from_maxima(&mut f, &[]);
    assert_eq!(f, zero());
    let deg = |az: f32, el_below: f32| {
        let (a, e) = (az.to_radians(), el_below.to_radians());
        Vector3::new(a.cos() * e.cos(), a.sin() * e.cos(), -e.sin())
    };
    grow_from_maxima(&mut f, &[deg(-20.0, 0.0), deg(20.0, 10.0)]);
    assert!((f.h_fov_deg - 40.0).abs() < 1e-3 && f.yaw_deg.abs() < 1e-3, "{f:?}");
    assert!(
        (f.v_fov_deg - 10.0).abs() < 1e-3 && (f.pitch_deg - 5.0).abs() < 1e-3,
        "{f:?}"
    );
    // Narrower in azimuth, taller in elevation: only the vertical part (and its centre) changes.
    grow_from_maxima(&mut f, &[deg(25.0, -10.0), deg(30.0, 20.0)]);
    assert!((f.h_fov_deg - 40.0).abs() < 1e-3 && f.yaw_deg.abs() < 1e-3, "{f:?}");
    assert!(
        (f.v_fov_deg - 30.0).abs() < 1e-3 && (f.pitch_deg - 5.0).abs() < 1e-3,
        "{f:?}"
    );
    let before = f;
    grow_from_maxima(&mut f, &[deg(1.0, 1.0), deg(2.0, 2.0)]);
    assert_eq!(f, before);
}

#[test]
fn a_camera_looking_backwards_wraps_its_centre() {
    let mut f = zero();
    // 170 and -170 deg: 20 deg apart across the back, centred at +-180.
    grow_from_maxima(
        &mut f,
        &[Vector3::new(-1.0, 0.176_327, 0.0), Vector3::new(-1.0, -0.176_327, 0.0)],
    );
    assert!((f.h_fov_deg - 20.0).abs() < 1e-2, "{f:?}");
    assert!((f.yaw_deg.abs() - 180.0).abs() < 1e-2, "{f:?}");
}

#[test]
fn update_from_cloud_selects_in_the_optical_frame() {
    // Facing East at 2 m: a near point low on the right and a far point high on the left.
    let pose = level(0.0, 0.0, 2.0, 0.0);
    let pts = [Vector3::new(2.0, -1.0, 1.0), Vector3::new(10.0, 3.0, 4.0)];
    let mut f = zero();
    update_from_cloud(&mut f, &pts, &pose, &mut Vec::new());
    let az_right = (-1f32).atan2(2.0).to_degrees();
    let az_left = 3f32.atan2(10.0).to_degrees();
    assert!((f.h_fov_deg - (az_left - az_right)).abs() < 1e-3, "{f:?}");
    assert!((f.yaw_deg - (az_left + az_right) / 2.0).abs() < 1e-3, "{f:?}");
    let below = 1f32.atan2(5f32.sqrt()).to_degrees();
    let above = -(2f32.atan2(109f32.sqrt()).to_degrees());
    assert!((f.pitch_deg - (below + above) / 2.0).abs() < 1e-3, "{f:?}");
}
