//! Tests of the star planner: AV's bar-obstacle known answer, path ordering and obstacle avoidance.

use super::*;
use crate::params::CostParams;

fn bar_cloud() -> Vec<Vector3<f32>> {
    // AV StarPlannerTests: a horizontal bar x 0..2.5, y = 2, z 3.5..4.5 sampled every 5 cm.
    let mut pts = Vec::new();
    let mut x = 0.0f32;
    while x < 2.5 {
        let mut z = 3.5f32;
        while z < 4.5 {
            pts.push(Vector3::new(x, 2.0, z));
            z += 0.05;
        }
        x += 0.05;
    }
    pts
}

fn inside_bar(n: &Vector3<f32>) -> bool {
    n.x > 0.0 && n.x < 2.5 && n.y > 1.9 && n.y < 2.1 && n.z > 3.5 && n.z < 4.5
}

#[test]
fn known_answer_av_build_tree_around_bar() {
    for cost in [CostParams::struct_defaults(), CostParams::default()] {
        let params = PlannerParams {
            cost,
            children_per_node: 2,
            n_expanded_nodes: 10,
            tree_node_distance_m: 1.0,
            ..Default::default()
        };
        let cloud = PointMemory::from_points(&bar_cloud());
        let goal = Vector3::new(2.0, 14.0, 4.0);
        let mut position = Vector3::new(1.2, 0.4, 4.0);
        let mut sp = StarPlanner::new();
        let mut min_dist = f32::INFINITY;
        for _ in 0..15 {
            let inputs = TreeInputs {
                position,
                velocity: Vector3::zeros(),
                goal,
                closest_pt: goal,
            };
            sp.build(&cloud, &inputs, &params);
            for n in sp.nodes() {
                assert!(
                    !inside_bar(&n.position_enu),
                    "node inside the bar: {:?}",
                    n.position_enu
                );
            }
            let d = (goal - position).norm();
            assert!(d < min_dist * 1.1, "distance to goal grew: {d} vs {min_dist}");
            min_dist = min_dist.min(d);
            position = sp.nodes()[1].position_enu;
        }
        assert!(min_dist < 12.0, "made progress: {min_dist}");
    }
}

#[test]
fn path_is_deepest_first_root_last_with_two_metre_edges() {
    let params = PlannerParams::default();
    let cloud = PointMemory::from_points(&bar_cloud());
    let root = Vector3::new(1.2, -3.0, 4.0);
    let inputs = TreeInputs {
        position: root,
        velocity: Vector3::new(0.0, 1.0, 0.0),
        goal: Vector3::new(2.0, 30.0, 4.0),
        closest_pt: Vector3::new(2.0, 30.0, 4.0),
    };
    let mut sp = StarPlanner::new();
    let path = sp.build(&cloud, &inputs, &params).to_vec();
    assert!(path.len() >= 3);
    assert_eq!(*path.last().unwrap_or(&Vector3::zeros()), root);
    for w in path.windows(2) {
        assert!(((w[0] - w[1]).norm() - 2.0).abs() < 1e-4);
    }
    let nodes = sp.nodes();
    let deepest = nodes.iter().filter(|n| !n.closed).map(|n| n.depth).max().unwrap_or(0);
    assert_eq!(path.len() as u32, deepest + 1);
    // First open node of maximal depth.
    let end = nodes.iter().position(|n| !n.closed && n.depth == deepest).unwrap_or(0);
    assert_eq!(path[0], nodes[end].position_enu);
    assert_eq!(sp.expanded(), 40);
    assert!(nodes.len() <= 1 + 40 * 8);
    // No two nodes closer than 0.2 m.
    for (i, a) in nodes.iter().enumerate() {
        for b in &nodes[i + 1..] {
            assert!((a.position_enu - b.position_enu).norm() >= 0.2);
        }
    }
    // Parents precede children and depths count edges.
    for (i, n) in nodes.iter().enumerate().skip(1) {
        assert!(n.parent < i);
        assert_eq!(n.depth, nodes[n.parent].depth + 1);
    }
}

#[test]
fn free_space_heads_for_the_goal() {
    let params = PlannerParams::default();
    let cloud = PointMemory::from_points(&[]);
    let root = Vector3::new(0.0, 0.0, 5.0);
    let goal = Vector3::new(20.0, 20.0, 5.0);
    let mut sp = StarPlanner::new();
    let path = sp
        .build(
            &cloud,
            &TreeInputs {
                position: root,
                velocity: Vector3::zeros(),
                goal,
                closest_pt: goal,
            },
            &params,
        )
        .to_vec();
    let first = path[path.len() - 2];
    let dir = (first - root).normalize();
    assert!(dir.dot(&(goal - root).normalize()) > 0.99, "{dir:?}");
}

#[test]
fn tree_never_enters_a_box_in_front() {
    // A 6 m wide, 4 m deep, 8 m high box 5 m North of the vehicle, seen as its surface points, plus a floor.
    let mut pts = Vec::new();
    for i in 0..=60 {
        for k in 0..=80 {
            let (x, z) = (-3.0 + i as f32 * 0.1, k as f32 * 0.1);
            pts.push(Vector3::new(x, 5.0, z));
            pts.push(Vector3::new(x, 9.0, z));
        }
        for j in 0..=40 {
            pts.push(Vector3::new(-3.0 + i as f32 * 0.1, 5.0 + j as f32 * 0.1, 8.0));
        }
    }
    for j in 0..=40 {
        for k in 0..=80 {
            pts.push(Vector3::new(-3.0, 5.0 + j as f32 * 0.1, k as f32 * 0.1));
            pts.push(Vector3::new(3.0, 5.0 + j as f32 * 0.1, k as f32 * 0.1));
        }
    }
    for i in -30..=30 {
        for j in -10..=40 {
            pts.push(Vector3::new(i as f32 * 0.5, j as f32 * 0.5, 0.0));
        }
    }
    let cloud = PointMemory::from_points(&pts);
    let params = PlannerParams::default();
    let goal = Vector3::new(0.0, 25.0, 3.0);
    let mut sp = StarPlanner::new();
    let inputs = TreeInputs {
        position: Vector3::new(0.0, 0.0, 3.0),
        velocity: Vector3::zeros(),
        goal,
        closest_pt: goal,
    };
    sp.build(&cloud, &inputs, &params);
    for n in sp.nodes() {
        let p = n.position_enu;
        let inside = p.x > -3.0 && p.x < 3.0 && p.y > 5.0 && p.y < 9.0 && p.z < 8.0;
        assert!(!inside, "node inside the box: {p:?}");
        assert!(p.z > 0.0, "node under the floor: {p:?}");
    }
}

#[test]
fn sqrt_threshold_is_exact() {
    for limit in [0.2f32, 15.0, 1.0, 0.3] {
        let t = sqrt_threshold(limit);
        assert!(t.sqrt() >= limit);
        assert!(t.next_down().sqrt() < limit);
    }
}

#[test]
fn reusing_the_root_histogram_gives_the_same_tree() {
    let mut pts = bar_cloud();
    pts.extend((0..400).map(|i| Vector3::new((i % 20) as f32 - 10.0, (i / 20) as f32 - 3.0, 0.0)));
    let cloud = PointMemory::from_points(&pts);
    let params = PlannerParams::default();
    let inputs = TreeInputs {
        position: Vector3::new(1.2, 0.4, 4.0),
        velocity: Vector3::new(0.0, 1.5, 0.0),
        goal: Vector3::new(2.0, 14.0, 4.0),
        closest_pt: Vector3::new(2.0, 14.0, 4.0),
    };
    let (xs, ys, zs) = cloud.soa();
    let mut root = Histogram::new();
    root.build_from_soa(xs, ys, zs, &inputs.position, &mut HistogramScratch::default());
    let (mut a, mut b) = (StarPlanner::new(), StarPlanner::new());
    let pa = a.build(&cloud, &inputs, &params).to_vec();
    let pb = b
        .build_with_root_histogram(&cloud, &inputs, &params, Some(&root))
        .to_vec();
    assert_eq!(pa, pb);
    assert_eq!(a.nodes(), b.nodes());
}
