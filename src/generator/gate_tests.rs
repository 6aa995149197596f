use super::*;
use crate::generator::{Generator, GeneratorConfig};
use crate::geometry::footprint_distance;
use crate::lfs::cp_params::DEFAULT_CP_DIST_M;
use crate::model::TestCase;

fn case(n: u32) -> TestCase {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("missions/mission{n}.yaml"));
    TestCase::load(&path).unwrap()
}

fn gate_generator(n: u32, seed: u64) -> Generator {
    let cfg = GeneratorConfig {
        family: Family::Gate,
        ..GeneratorConfig::default()
    };
    Generator::new(&case(n), cfg, seed).unwrap()
}

#[test]
fn gates_are_valid_deterministic_and_leave_a_gap_around_twice_cp_dist() {
    for n in [2, 5] {
        let g = gate_generator(n, 7);
        for index in 0..20 {
            let p = g.sample(index).unwrap();
            assert_eq!(p.obstacles.len(), 2);
            // sample() only returns layouts that pass every competition rule; the same seed, the same layout.
            assert_eq!(gate_generator(n, 7).sample(index).unwrap().obstacles, p.obstacles);
            let gap = footprint_distance(&p.obstacles[0].footprint(), &p.obstacles[1].footprint());
            let want = 2.0 * DEFAULT_CP_DIST_M;
            assert!(
                gap >= 0.75 * want - 1e-6 && gap <= 1.25 * want + 1e-6,
                "mission {n} test {index}: gap {gap}"
            );
            assert!((p.draw.gap_m - gap).abs() < 1e-6, "{} vs {gap}", p.draw.gap_m);
        }
        assert_ne!(
            gate_generator(n, 8).sample(0).unwrap().obstacles,
            gate_generator(n, 7).sample(0).unwrap().obstacles
        );
    }
}

#[test]
fn the_gap_follows_the_case_s_cp_dist() {
    let mut c = case(2);
    c.params.push(crate::model::Param {
        name: "CP_DIST".into(),
        value: 3.0,
    });
    let cfg = GeneratorConfig {
        family: Family::Gate,
        ..GeneratorConfig::default()
    };
    let p = Generator::new(&c, cfg, 1).unwrap().sample(0).unwrap();
    assert!(
        p.draw.gap_m >= 4.5 - 1e-9 && p.draw.gap_m <= 7.5 + 1e-9,
        "{}",
        p.draw.gap_m
    );
}
