//! Criterion bench of one 3DVFH* planner cycle (cloud processing + histogram + cost + tree + waypoint) on a
//! realistic synthetic frame: a 64 x 48 ray grid of the 59-degree camera hitting a floor and two boxes.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use nalgebra::Vector3;
use prgenuav::lfs::cost::{CostInputs, CostScratch, cost_matrix};
use prgenuav::lfs::histogram::{Histogram, HistogramScratch};
use prgenuav::lfs::planner::{PlanInput, Planner, VehicleState};
use prgenuav::lfs::waypoint::{NavState, WaypointGenerator, WaypointInput};
use prgenuav::lfs::{CostParams, PlannerParams};

/// Axis-aligned box, ENU min/max corners.
struct Aabb {
    min: Vector3<f32>,
    max: Vector3<f32>,
}

fn ray_box(o: &Vector3<f32>, d: &Vector3<f32>, b: &Aabb) -> Option<f32> {
    let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
    for i in 0..3 {
        let inv = 1.0 / d[i];
        let (mut a, mut c) = ((b.min[i] - o[i]) * inv, (b.max[i] - o[i]) * inv);
        if a > c {
            std::mem::swap(&mut a, &mut c);
        }
        t0 = t0.max(a);
        t1 = t1.min(c);
    }
    (t0 <= t1).then_some(t0)
}

/// World points seen by a level camera at `pos` looking along ENU yaw `yaw` (64 x 48 rays, 59 deg HFOV,
/// depth along the optical axis kept in 0.2..20 m).
fn frame(pos: &Vector3<f32>, yaw: f32, boxes: &[Aabb]) -> Vec<Vector3<f32>> {
    let (w, h) = (64usize, 48usize);
    let fl = w as f32 / (2.0 * (59.0f32.to_radians() / 2.0).tan());
    let fwd = Vector3::new(yaw.cos(), yaw.sin(), 0.0);
    let left = Vector3::new(-yaw.sin(), yaw.cos(), 0.0);
    let up = Vector3::new(0.0, 0.0, 1.0);
    let mut pts = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let x = (i as f32 - (w as f32 - 1.0) / 2.0) / fl;
            let y = (j as f32 - (h as f32 - 1.0) / 2.0) / fl;
            let d = fwd - left * x - up * y;
            let mut t = if d.z < 0.0 { -pos.z / d.z } else { f32::INFINITY };
            for b in boxes {
                if let Some(tb) = ray_box(pos, &d, b) {
                    t = t.min(tb);
                }
            }
            // d has unit forward component, so t is the depth along the optical axis.
            if t > 0.2 && t < 20.0 {
                pts.push(pos + d * t);
            }
        }
    }
    pts
}

fn scene() -> Vec<Aabb> {
    vec![
        Aabb {
            min: Vector3::new(-4.0, 8.0, 0.0),
            max: Vector3::new(1.0, 11.0, 10.0),
        },
        Aabb {
            min: Vector3::new(3.0, 14.0, 0.0),
            max: Vector3::new(7.0, 16.0, 8.0),
        },
    ]
}

const GOAL: Vector3<f32> = Vector3::new(0.0, 40.0, 3.5);
const YAW_NORTH: f32 = std::f32::consts::FRAC_PI_2;

fn state(y: f32) -> VehicleState {
    VehicleState {
        position_enu: Vector3::new(0.0, y, 3.5),
        velocity_enu: Vector3::new(0.0, 3.0, 0.0),
        yaw_enu_rad: YAW_NORTH,
        pitch_rad: 0.0,
    }
}

/// A planner after a few frames of approach, so its memory holds remembered floor points too.
fn warmed_up() -> (Planner, WaypointGenerator, Vec<Vector3<f32>>) {
    let boxes = scene();
    let params = PlannerParams::default();
    let mut planner = Planner::new(params.clone()).expect("default params are valid");
    let mut wg = WaypointGenerator::with_fovs(params.fovs.clone());
    let mut y = -6.0;
    let mut t = 0.0;
    for k in 0..8 {
        let s = state(y);
        // Look around a bit so memory outside the FOV fills.
        let yaw = YAW_NORTH + [0.0, 0.5, -0.5, 0.0][k % 4];
        let pts = frame(&s.position_enu, yaw, &boxes);
        let s = VehicleState { yaw_enu_rad: yaw, ..s };
        planner.update_cloud(&pts, &s, 0.1).expect("finite state");
        let input = PlanInput {
            state: s,
            goal_enu: GOAL,
            prev_goal_enu: GOAL,
            now_s: t,
        };
        let plan = planner.plan(&input).expect("finite input").clone();
        let wi = waypoint_input(&plan, s);
        wg.step(&wi, t);
        y += 0.3;
        t += 0.1;
    }
    let s = state(y);
    let pts = frame(&s.position_enu, YAW_NORTH, &boxes);
    (planner, wg, pts)
}

fn waypoint_input(plan: &prgenuav::lfs::planner::Plan, s: VehicleState) -> WaypointInput<'_> {
    WaypointInput {
        state: s,
        goal_enu: GOAL,
        prev_goal_enu: GOAL,
        stay: false,
        is_airborne: true,
        nav_state: NavState::Mission,
        is_land_waypoint: false,
        is_takeoff_waypoint: false,
        desired_vel_enu: None,
        plan,
    }
}

fn bench(c: &mut Criterion) {
    let (planner, wg, pts) = warmed_up();
    let s = state(-3.6);
    {
        let mut p = planner.clone();
        p.update_cloud(&pts, &s, 0.1).expect("finite state");
        let path_len = p
            .plan(&PlanInput {
                state: s,
                goal_enu: GOAL,
                prev_goal_enu: GOAL,
                now_s: 1.0,
            })
            .expect("ok")
            .path_enu
            .len();
        eprintln!(
            "frame: {} rays hit, memory {} points, tree {} nodes, path {} nodes",
            pts.len(),
            p.memory().len(),
            p.tree().len(),
            path_len
        );
    }

    c.bench_function("planner_cycle", |b| {
        b.iter_batched(
            || (planner.clone(), wg.clone()),
            |(mut p, mut g)| {
                p.update_cloud(black_box(&pts), &s, 0.1).expect("finite state");
                let plan = p
                    .plan(&PlanInput {
                        state: s,
                        goal_enu: GOAL,
                        prev_goal_enu: GOAL,
                        now_s: 1.0,
                    })
                    .expect("ok");
                let out = g.step(&waypoint_input(plan, s), 1.0);
                black_box(out)
            },
            BatchSize::SmallInput,
        )
    });

    let mut p = planner.clone();
    p.update_cloud(&pts, &s, 0.1).expect("finite state");
    let (xs, ys, zs) = p.memory().soa();
    let origin = s.position_enu;
    let mut hist = Histogram::new();
    let mut hs = HistogramScratch::default();
    c.bench_function("histogram_build", |b| {
        b.iter(|| hist.build_from_soa(black_box(xs), ys, zs, &origin, &mut hs))
    });
    hist.build_from_soa(xs, ys, zs, &origin, &mut hs);
    let inputs = CostInputs {
        goal: GOAL,
        origin,
        velocity: s.velocity_enu,
        closest_pt: GOAL,
    };
    let mut cs = CostScratch::default();
    let mut total = Box::new([0.0f32; 1800]);
    c.bench_function("cost_matrix", |b| {
        b.iter(|| {
            cost_matrix(
                black_box(&hist),
                &inputs,
                &CostParams::default(),
                7,
                0.2,
                15.0,
                &mut cs,
                &mut total,
            )
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
