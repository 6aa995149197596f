use super::*;
use crate::model::Obstacle;
use prgenuav_planner::cloud::{CloudPose, PointMemory};
use prgenuav_planner::histogram::Histogram;
use prgenuav_planner::params::PlannerParams;

const KEEP: KeepRange = KeepRange {
    min_m: 0.2,
    max_m: 15.0,
};

fn processed(points: &[Vector3<f32>], pose: &CameraPose, cam: &Camera) -> PointMemory {
    let params = PlannerParams {
        fovs: vec![cam.fov()],
        ..Default::default()
    };
    let mut m = PointMemory::new();
    let p = pose.position_enu;
    let cp = CloudPose {
        position_enu: Vector3::new(p.x as f32, p.y as f32, p.z as f32),
        yaw_enu_deg: pose.yaw_enu_rad.to_degrees() as f32,
        pitch_deg: pose.pitch_rad.to_degrees() as f32,
    };
    m.process(points, &cp, &params, 0.1);
    m
}

fn obstacles() -> Vec<Obstacle> {
    vec![
        Obstacle::new(10.0, 5.0, 20.0, 10.0, 20.0, 0.0),
        Obstacle::new(12.0, 4.0, 8.0, -6.0, 24.0, 35.0),
        Obstacle::new(3.0, 3.0, 12.0, 2.0, 8.0, 80.0),
    ]
}

fn poses() -> Vec<CameraPose> {
    let p = |e: f64, n: f64, z: f64, yaw_deg: f64| CameraPose::level(Vector3::new(e, n, z), yaw_deg.to_radians());
    vec![
        p(5.0, -5.0, 10.0, 45.0),
        p(12.0, 0.0, 10.0, 0.0),
        p(14.0, -1.0, 3.0, 30.0),
        p(25.0, 6.0, 9.5, 160.0),
        p(4.0, 4.0, 1.5, -45.0),
        p(18.0, -14.0, 10.0, 45.0),
        p(30.0, 2.0, 4.0, 179.9),
        p(8.0, 14.0, 10.0, -60.0),
    ]
}

#[test]
fn floor_f64_is_std_floor() {
    let mut s: u64 = 99;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        f64::from_bits(s)
    };
    let edge = [
        0.0,
        -0.0,
        0.5,
        -0.5,
        1.0,
        -1.0,
        2.5,
        -2.5,
        4.5e15,
        -4.5e15,
        1e300,
        -1e-300,
        f64::INFINITY,
    ];
    for x in edge.into_iter().chain((0..100_000).map(|_| next())) {
        let (a, b) = (floor_f64(x), x.floor());
        assert!(
            a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
            "{x}: {a} vs {b}"
        );
    }
    for i in -2000..2000 {
        let x = i as f64 * 0.37;
        assert_eq!(floor_f64(x).to_bits(), x.floor().to_bits(), "{x}");
    }
}

#[test]
fn fast_cloud_equals_full_render_cloud() {
    let scene = Scene::new(&obstacles());
    for cam in [Camera::hfs(), Camera::v2019(), Camera::d455()] {
        let mut scratch = FastRenderScratch::default();
        for pose in poses() {
            let full = cloud_from_depth(&cam, &pose, &render_depth(&scene, &cam, &pose).unwrap());
            let mut fast = Vec::new();
            render_cloud(&scene, &cam, &pose, KEEP, &mut scratch, &mut fast).unwrap();
            let a = processed(&full, &pose, &cam);
            let b = processed(&fast, &pose, &cam);
            let pa: Vec<_> = a.points().map(|p| p.0).collect();
            let pb: Vec<_> = b.points().map(|p| p.0).collect();
            assert!(pa.len() > 20, "{} {:?}: only {} points", cam.name, pose, pa.len());
            let only_a: Vec<_> = pa.iter().filter(|p| !pb.contains(p)).collect();
            let only_b: Vec<_> = pb.iter().filter(|p| !pa.contains(p)).collect();
            assert!(
                only_a.is_empty() && only_b.is_empty(),
                "{} {pose:?}: full only {only_a:?}, fast only {only_b:?}",
                cam.name
            );
            assert_eq!(pa, pb, "{} {:?}", cam.name, pose);
            let o = Vector3::new(
                pose.position_enu.x as f32,
                pose.position_enu.y as f32,
                pose.position_enu.z as f32,
            );
            assert_eq!(Histogram::from_points(&pa, &o), Histogram::from_points(&pb, &o));
            assert!(
                fast.len() < full.len() / 10 || cam.name == "2019",
                "{} of {}",
                fast.len(),
                full.len()
            );
        }
        assert_eq!(scratch.fallbacks, 0);
    }
}

#[test]
fn fast_cloud_equals_full_render_cloud_on_random_poses() {
    use rand::{Rng, SeedableRng};
    let scene = Scene::new(&obstacles());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut scratch = FastRenderScratch::default();
    let mut checked = 0;
    for n in 0..60 {
        let cam = if n % 6 == 0 { Camera::hfs() } else { Camera::v2019() };
        let pose = CameraPose::level(
            Vector3::new(
                rng.random_range(-5.0..35.0),
                rng.random_range(-15.0..20.0),
                rng.random_range(0.3..14.0),
            ),
            rng.random_range(-3.2..3.2),
        );
        let Ok(img) = render_depth(&scene, &cam, &pose) else {
            continue;
        };
        let full = cloud_from_depth(&cam, &pose, &img);
        let mut fast = Vec::new();
        render_cloud(&scene, &cam, &pose, KEEP, &mut scratch, &mut fast).unwrap();
        let a: Vec<_> = processed(&full, &pose, &cam).points().collect();
        let b: Vec<_> = processed(&fast, &pose, &cam).points().collect();
        assert_eq!(a, b, "{} {pose:?}", cam.name);
        checked += 1;
    }
    assert!(checked > 40);
}

#[test]
fn near_box_and_pitch_fall_back_to_the_full_render() {
    let scene = Scene::new(&obstacles());
    let cam = Camera::v2019();
    let mut scratch = FastRenderScratch::default();
    let near = CameraPose::level(Vector3::new(20.0, 4.7, 5.0), 90f64.to_radians());
    let mut out = Vec::new();
    render_cloud(&scene, &cam, &near, KEEP, &mut scratch, &mut out).unwrap();
    let pitched = CameraPose {
        pitch_rad: 0.1,
        ..CameraPose::level(Vector3::new(0.0, 0.0, 10.0), 1.0)
    };
    render_cloud(&scene, &cam, &pitched, KEEP, &mut scratch, &mut out).unwrap();
    assert_eq!(scratch.fallbacks, 2);
    let inside = CameraPose::level(Vector3::new(20.0, 10.0, 5.0), 0.0);
    assert!(render_cloud(&scene, &cam, &inside, KEEP, &mut scratch, &mut out).is_err());
}
