//! The generator over thousands of seeds: every test valid, the paper's geometry exact, any SoI direction.

use prgenuav::generator::{Generator, GeneratorConfig, Placement, Side, Soi};
use prgenuav::geometry::V2;
use prgenuav::model::{Arena, Mission, Obstacle, SIM_HOME};
use prgenuav::rules::check_obstacles;
use proptest::prelude::*;

use super::{case, prgenuav, repo};

/// Unit long axis, long side and short side of a box.
fn long_axis(o: &Obstacle) -> (V2, f64, f64) {
    let r = o.position.r.to_radians();
    if o.size.l >= o.size.w {
        (V2::new(r.cos(), r.sin()), o.size.l, o.size.w)
    } else {
        (V2::new(-r.sin(), r.cos()), o.size.w, o.size.l)
    }
}

fn cross(a: V2, b: V2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Checks one placement against the rules and the paper's construction.
fn verify(p: &Placement, g: &Generator, mission: &Mission) {
    let cfg = GeneratorConfig::default();
    let v = check_obstacles(&p.obstacles, mission, &Arena::default());
    assert!(v.is_empty(), "test {} breaks rules: {v:#?}", p.index);
    let soi: &Soi = g.soi();
    let d = soi.direction();
    assert_eq!(p.obstacles.len(), 2 + usize::from(p.draw.third_ahead_m.is_some()));
    let (o1, o2) = (&p.obstacles[0], &p.obstacles[1]);
    let (u1, long1, short1) = long_axis(o1);
    let (u2, long2, short2) = long_axis(o2);
    assert!((short1 - cfg.width_m).abs() < 1e-12 && (short2 - cfg.width_m).abs() < 1e-12);
    assert!((o1.size.h - 20.0).abs() < 1e-12 && (o2.size.h - 20.0).abs() < 1e-12);
    // Where the SoI's line crosses obstacle 1's long axis: centre + s u1.
    let c1 = V2::new(o1.position.x, o1.position.y);
    let s = cross(V2::new(soi.start.x, soi.start.y) - c1, d) / cross(u1, d);
    let part_a = long1 / 2.0 - s.abs();
    let ratio = part_a / long1;
    assert!(
        (ratio - p.draw.split).abs() <= 1e-6 / 3.0,
        "test {}: split {ratio}",
        p.index
    );
    // The crossing lies on the SoI, between its ends.
    let at = c1 + u1 * s;
    let t = (at - V2::new(soi.start.x, soi.start.y)).dot(&d);
    assert!(t > 0.0 && t < soi.length(), "crossing outside the SoI: t {t}");
    // A points forward (acute with the flight direction), B makes the obtuse angle.
    let a_dir = u1 * s.signum();
    assert!(a_dir.dot(&d) > 0.0, "A part must lean towards the goal");
    assert!((-a_dir).dot(&d) < 0.0, "the SoI meets part B at an obtuse angle");
    let side = if cross(d, a_dir) > 0.0 { Side::Left } else { Side::Right };
    assert_eq!(side, g.a_side());
    // Obstacle 2: perpendicular and 1.75 x as long.
    let angle = u1.dot(&u2).abs().min(1.0).acos();
    assert!(
        (angle - std::f64::consts::FRAC_PI_2).abs() < 1e-9,
        "test {}: angle {angle}",
        p.index
    );
    assert!((long2 / long1 - cfg.length_factor).abs() < 1e-9);
    // Beyond the A end: obstacle 2's centre is further along A than obstacle 1's A end.
    let c2 = V2::new(o2.position.x, o2.position.y);
    assert!((c2 - at).dot(&a_dir) > part_a, "obstacle 2 must stand beyond the A end");
    if let Some(ahead) = p.draw.third_ahead_m {
        verify_third(p, soi, (o1, a_dir, at), ahead);
    }
}

/// The third obstacle: obstacle 1 mirrored across the SoI (same size, same angle to it, its short part on the
/// other side), crossing the SoI between its ends, `ahead` clear of the pair along the SoI.
fn verify_third(p: &Placement, soi: &Soi, (o1, a_dir, at): (&Obstacle, V2, V2), ahead: f64) {
    let cfg = GeneratorConfig::default();
    let d = soi.direction();
    let o3 = &p.obstacles[2];
    let (u3, long3, short3) = long_axis(o3);
    let (_, long1, _) = long_axis(o1);
    assert!((long3 - long1).abs() < 1e-9 && (short3 - cfg.width_m).abs() < 1e-12);
    let c3 = V2::new(o3.position.x, o3.position.y);
    let s = cross(V2::new(soi.start.x, soi.start.y) - c3, d) / cross(u3, d);
    let at3 = c3 + u3 * s;
    let t3 = (at3 - V2::new(soi.start.x, soi.start.y)).dot(&d);
    assert!(t3 > (at - V2::new(soi.start.x, soi.start.y)).dot(&d) && t3 <= soi.length() + 1e-9);
    let a3 = u3 * s.signum();
    assert!((long3 / 2.0 - s.abs()) / long3 - p.draw.split < 1e-6, "same split");
    assert!((a3.dot(&d) - a_dir.dot(&d)).abs() < 1e-9, "same angle to the SoI");
    assert!(cross(d, a3) * cross(d, a_dir) < 0.0, "its short part on the other side");
    // Clear of the pair along the SoI by `ahead` (so it neither overlaps nor touches them).
    let proj = |o: &Obstacle| {
        let f = o.footprint();
        let ps: Vec<f64> = f.corners().iter().map(|c| V2::new(c.x, c.y).dot(&d)).collect();
        (
            ps.iter().cloned().fold(f64::MAX, f64::min),
            ps.iter().cloned().fold(f64::MIN, f64::max),
        )
    };
    let pair_far = proj(o1).1.max(proj(&p.obstacles[1]).1);
    assert!(
        (proj(o3).0 - pair_far - ahead).abs() < 1e-6,
        "test {}: not {ahead} m clear",
        p.index
    );
    assert!(ahead >= cfg.third_ahead_m.min - 1e-12 && ahead <= cfg.third_ahead_m.max + 1e-12);
}

fn generator_for(mission: &Mission, seed: u64) -> Generator {
    Generator::for_mission(mission, Arena::default(), GeneratorConfig::default(), seed).expect("generator")
}

#[test]
fn thousands_of_seeds_on_missions_1_to_7() {
    for n in 1..=7 {
        let mission = case(n).mission;
        for seed in 0..3u64 {
            let g = generator_for(&mission, seed);
            for i in 0..700 {
                verify(
                    &g.sample(i)
                        .unwrap_or_else(|e| panic!("mission{n} seed {seed} test {i}: {e}")),
                    &g,
                    &mission,
                );
            }
        }
    }
}

/// A synthetic mission through local points (x North, y East), 10 m up.
fn mission_through(points: &[(f64, f64)]) -> Mission {
    Mission::through_local_points(points, 10.0, SIM_HOME)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// SoIs of every slope sign and direction: up or down the arena, leaning either way, steep or vertical.
    #[test]
    fn any_soi_direction(x0 in -30.0f64..20.0, x1 in -30.0f64..20.0, vertical in any::<bool>(),
                         reversed in any::<bool>(), seed in 0u64..1000) {
        let x1 = if vertical { x0 } else { x1 };
        let (mut a, mut b) = ((x0, 5.0), (x1, 45.0));
        if reversed {
            std::mem::swap(&mut a, &mut b);
        }
        let mission = mission_through(&[(0.0, 0.0), a, b, (0.0, 0.0)]);
        let g = generator_for(&mission, seed);
        for i in 0..5 {
            verify(&g.sample(i).unwrap(), &g, &mission);
        }
    }
}

#[test]
fn near_horizontal_path_uses_the_longest_stretch_inside() {
    // Never crosses both y borders inside the arena: the fallback SoI still gets a valid S-pair.
    let mission = mission_through(&[(-60.0, 18.0), (45.0, 32.0)]);
    let g = generator_for(&mission, 7);
    assert_eq!(g.soi().kind, prgenuav::generator::SoiKind::LongestInside);
    for i in 0..200 {
        let p = g.sample(i).unwrap();
        assert!(check_obstacles(&p.obstacles, &mission, &Arena::default()).is_empty());
    }
    let outside = mission_through(&[(100.0, 0.0), (100.0, 60.0)]);
    let e = Generator::for_mission(&outside, Arena::default(), GeneratorConfig::default(), 0).unwrap_err();
    assert!(e.to_string().contains("never flies through"), "{e}");
}

#[test]
fn same_seed_same_tests_different_seed_different_tests() {
    let mission = case(2).mission;
    let (a, b, c) = (
        generator_for(&mission, 42),
        generator_for(&mission, 42),
        generator_for(&mission, 43),
    );
    for i in 0..50 {
        assert_eq!(a.sample(i).unwrap(), b.sample(i).unwrap());
        assert_ne!(a.sample(i).unwrap().obstacles, c.sample(i).unwrap().obstacles);
    }
    // Order does not matter: test 9 is test 9 whether drawn first or last.
    assert_eq!(a.sample(9).unwrap(), generator_for(&mission, 42).sample(9).unwrap());
}

#[test]
fn sample_cli_is_byte_identical_per_seed_and_valid() {
    let dir = tempfile::tempdir().unwrap();
    let run = |seed: &str, out: &str| {
        let out = dir.path().join(out);
        let (code, stdout, err) = prgenuav(&[
            "sample",
            "missions/mission3.yaml",
            "--count",
            "5",
            "--seed",
            seed,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{err}");
        assert!(
            stdout.contains(&format!("output folder: {}", out.display())),
            "{stdout}"
        );
        (0..5)
            .map(|i| std::fs::read(out.join(format!("test_{i}.yaml"))).unwrap())
            .collect::<Vec<_>>()
    };
    let (a, b, c) = (run("5", "a"), run("5", "b"), run("6", "c"));
    assert_eq!(a, b);
    assert_ne!(a, c);
    for i in 0..5 {
        let f = dir.path().join(format!("a/test_{i}.yaml"));
        let (code, out, err) = prgenuav(&["check", f.to_str().unwrap()]);
        assert_eq!(code, 0, "{out}{err}");
    }
    let _ = repo();
}

/// `--family extended` writes tests with three obstacles where the mission leaves room, and `check` takes them.
#[test]
fn sample_cli_extended_family_writes_valid_three_obstacle_tests() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let (code, _, err) = prgenuav(&[
        "sample",
        "missions/mission2.yaml",
        "--count",
        "40",
        "--family",
        "extended",
        "--seed",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let mut three = 0;
    for i in 0..40 {
        let f = out.join(format!("test_{i}.yaml"));
        let text = std::fs::read_to_string(&f).unwrap();
        three += usize::from(text.matches("size:").count() == 3);
        let (code, out, err) = prgenuav(&["check", f.to_str().unwrap()]);
        assert_eq!(code, 0, "{out}{err}");
    }
    assert!(three > 0, "no test with three obstacles in 40");
    let (code, _, err) = prgenuav(&["sample", "missions/mission2.yaml", "--count", "2", "--family", "wide"]);
    assert_eq!(code, 2);
    assert!(err.contains("--family"), "{err}");
}

#[test]
fn sample_cli_bad_arguments() {
    let (code, _, err) = prgenuav(&["sample", "missions/mission2.yaml", "--count", "0"]);
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = prgenuav(&["sample", "missions/mission2.yaml", "--count", "2", "--gap", "5,1"]);
    assert_eq!(code, 2);
    assert!(err.contains("gap_m"), "{err}");
    let (code, _, err) = prgenuav(&["sample", "missions/nope.yaml", "--count", "2"]);
    assert_eq!(code, 2);
    assert!(err.contains("nope.yaml"), "{err}");
    let toml_dir = tempfile::tempdir().unwrap();
    let cfg = toml_dir.path().join("g.toml");
    std::fs::write(&cfg, "gap_m = { min = 2.5, max = 3.0 }\nbogus = 1\n").unwrap();
    let (code, _, err) = prgenuav(&[
        "sample",
        "missions/mission2.yaml",
        "--count",
        "2",
        "--config",
        cfg.to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("bogus"), "{err}");
}

#[test]
fn toml_and_flags_change_the_draw_ranges() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let (code, stdout, err) = prgenuav(&[
        "sample",
        "missions/mission2.yaml",
        "--count",
        "20",
        "--gap",
        "3,3.1",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    for t in j["tests"].as_array().unwrap() {
        let gap = t["draw"]["gap_m"].as_f64().unwrap();
        assert!((3.0..=3.1).contains(&gap), "{gap}");
    }
    assert!(j["diversity"].as_f64().unwrap() > 0.5);
}

/// An adapted draw distribution (all of the gap's mass in its lowest tenth, the angle's in its highest) keeps
/// the paper's construction and every rule, is deterministic per seed, and moves the draws where it says.
#[test]
fn an_adapted_distribution_keeps_the_rules_and_shapes_the_draws() {
    use prgenuav::generator::DrawDistribution;
    let mut dist = DrawDistribution::uniform();
    dist.weights[3] = [0.0; 10];
    dist.weights[3][0] = 1.0;
    dist.weights[2] = [0.0; 10];
    dist.weights[2][9] = 1.0;
    dist.validate().unwrap();
    let cfg = GeneratorConfig::default();
    for n in 1..=3 {
        let c = case(n);
        let g = Generator::new(&c, cfg.clone(), 5)
            .unwrap()
            .with_distribution(dist.clone());
        for i in 0..200 {
            let p = g.sample(i).unwrap();
            verify(&p, &g, &c.mission);
            assert!(p.draw.gap_m <= cfg.gap_m.min + 0.1 * (cfg.gap_m.max - cfg.gap_m.min) + 1e-9);
            assert!(p.draw.angle_deg >= cfg.angle_deg.max - 0.1 * (cfg.angle_deg.max - cfg.angle_deg.min) - 1e-9);
            assert_eq!(g.sample(i).unwrap(), p, "same seed, same distribution, same test");
        }
    }
    // The uniform distribution is the paper's generator, bit for bit.
    let c = case(2);
    let plain = Generator::new(&c, cfg.clone(), 9).unwrap();
    let uniform = Generator::new(&c, cfg, 9)
        .unwrap()
        .with_distribution(DrawDistribution::uniform());
    for i in 0..50 {
        assert_eq!(plain.sample(i).unwrap(), uniform.sample(i).unwrap());
    }
}

/// Neighbour proposals (the adapted campaign's draws around its failing flights) keep every rule, stay in
/// their parent's box and are deterministic per seed, on every mission.
#[test]
fn neighbour_proposals_keep_the_rules_and_stay_near_their_parent() {
    use prgenuav::generator::{Neighbourhood, Proposal};
    let cfg = GeneratorConfig::default();
    for n in 1..=3 {
        let c = case(n);
        let plain = Generator::new(&c, cfg.clone(), 11).unwrap();
        for parent_index in [0, 7] {
            let centre = plain.sample(parent_index).unwrap().draw.unit;
            let around = Neighbourhood {
                centre,
                half_width: 0.1,
            };
            let g = plain.clone().with_proposal(Proposal::Around(around));
            for i in 100..160 {
                let p = g.sample(i).unwrap();
                verify(&p, &g, &c.mission);
                for (u, c) in p.draw.unit.iter().zip(&centre) {
                    assert!((u - c).abs() <= 0.1 + 1e-12, "{:?}", p.draw.unit);
                }
                assert_eq!(g.sample(i).unwrap(), p, "same seed, same parent, same test");
            }
        }
    }
}

/// A campaign's filter on the draws (the adapted campaign asks its boxes for children that are no
/// near-duplicate of a flown test): what it takes obeys it and every rule, the same filter gives the same test,
/// and a filter that takes nothing is a bounded, named refusal.
#[test]
fn a_filtered_draw_obeys_the_filter_and_the_rules() {
    use prgenuav::generator::{GenerateError, Neighbourhood, Proposal};
    use prgenuav::geometry::union_iou;
    let iou = |a: &[Obstacle], b: &[Obstacle]| {
        let f = |o: &[Obstacle]| o.iter().map(Obstacle::footprint).collect::<Vec<_>>();
        union_iou(&f(a), &f(b))
    };
    for n in 1..=3 {
        let c = case(n);
        let plain = Generator::new(&c, GeneratorConfig::default(), 5).unwrap();
        let parent = plain.sample(3).unwrap();
        let around = Neighbourhood {
            centre: parent.draw.unit,
            half_width: 0.15,
        };
        let g = plain.clone().with_proposal(Proposal::Around(around));
        let mut refused_plain = 0;
        for i in 200..240 {
            let distinct = |o: &[Obstacle]| iou(o, &parent.obstacles) <= 0.5;
            let p = g.sample_where(i, 64, distinct).unwrap();
            verify(&p, &g, &c.mission);
            assert!(iou(&p.obstacles, &parent.obstacles) <= 0.5, "mission {n}, test {i}");
            assert_eq!(g.sample_where(i, 64, distinct).unwrap(), p);
            refused_plain += usize::from(!distinct(&g.sample(i).unwrap().obstacles));
            // Accepting everything is the plain draw.
            assert_eq!(g.sample_where(i, 64, |_| true).unwrap(), g.sample(i).unwrap());
        }
        assert!(
            refused_plain > 0,
            "mission {n}: some plain children are near-duplicates of the parent"
        );
        match g.sample_where(7, 5, |_| false) {
            Err(GenerateError::Refused { index: 7, asked: 5 }) => {}
            other => panic!("{other:?}"),
        }
    }
}

/// The extended family draws the split and, where its draw and the case allow, a third obstacle: every test
/// keeps the rules and the construction, the same seed gives the same test, and the paper's family is what
/// `Generator::new` draws.
#[test]
fn the_extended_family_draws_the_split_and_a_third_obstacle_where_the_case_allows() {
    use prgenuav::generator::Family;
    let cfg = GeneratorConfig::default();
    for n in 1..=7 {
        let c = case(n);
        let paper = Generator::new(&c, cfg.clone(), 3).unwrap();
        assert_eq!(paper.family(), Family::Paper);
        let extended = paper.clone().with_family(Family::Extended);
        let (mut thirds, mut splits) = (0, Vec::new());
        for i in 0..300 {
            let p = extended.sample(i).unwrap();
            verify(&p, &extended, &c.mission);
            assert_eq!(extended.sample(i).unwrap(), p, "same seed, same test");
            thirds += usize::from(p.obstacles.len() == 3);
            splits.push(p.draw.split);
            let q = paper.sample(i).unwrap();
            assert_eq!((q.obstacles.len(), q.draw.split), (2, cfg.split), "the paper's family");
        }
        let lo = splits.iter().cloned().fold(1.0, f64::min);
        let hi = splits.iter().cloned().fold(0.0, f64::max);
        assert!(lo < 0.25 && hi > 0.4, "mission {n}: splits {lo}..{hi}");
        // A third obstacle fits on the long segments of interest only.
        eprintln!("mission {n}: {thirds} of 300 tests with a third obstacle");
        if n <= 3 {
            assert!(thirds > 0, "mission {n}: no third obstacle in 300 tests");
        }
    }
}
