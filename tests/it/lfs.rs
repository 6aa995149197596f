//! The low-fidelity simulator's commands: `render`, `simulate` and `fidelity`, including bad input.

use prgenuav::model::Obstacle;

use super::{prgenuav, repo, temp_file, test_file, valid_pair};

fn npy_shape(bytes: &[u8]) -> String {
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let n = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + n]).unwrap();
    assert!(header.contains("'descr': '<f4'"), "{header}");
    let s = header.split("'shape': (").nth(1).unwrap();
    s[..s.find(')').unwrap()].to_string()
}

#[test]
fn render_writes_depth_and_points() {
    let (dir, test) = test_file(2, valid_pair());
    let out = dir.path().join("d.npy");
    let pts = dir.path().join("c.csv");
    // 10 m South-West of the first box's centre, looking at it (bearing 45 degrees).
    let (code, stdout, err) = prgenuav(&[
        "render",
        test.to_str().unwrap(),
        "--pose",
        "-12,13,5,45",
        "--camera",
        "2019",
        "--out-file",
        out.to_str().unwrap(),
        "--points",
        pts.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout} {err}");
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(npy_shape(&bytes), "48, 64");
    let hlen = 10 + u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let depths: Vec<f32> = bytes[hlen..]
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(depths.len(), 64 * 48);
    let valid: Vec<f32> = depths.iter().copied().filter(|d| d.is_finite()).collect();
    assert!(valid.len() > 100 && depths.iter().any(|d| d.is_nan()));
    assert!(valid.iter().all(|d| (0.5..=18.0).contains(d)));
    let csv = std::fs::read_to_string(&pts).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("x,y,z"));
    for l in lines {
        let v: Vec<f64> = l.split(',').map(|c| c.parse().unwrap()).collect();
        // NED: z is down, so every point is at or below 0 (ground) and above -20 (box top).
        assert!(v[2] <= 1e-3 && v[2] >= -20.001, "{l}");
    }
}

#[test]
fn render_rejects_bad_poses_and_options() {
    let (dir, test) = test_file(2, valid_pair());
    let out = dir.path().join("d.npy");
    let run = |pose: &str, camera: &str| {
        prgenuav(&[
            "render",
            test.to_str().unwrap(),
            "--pose",
            pose,
            "--camera",
            camera,
            "--out-file",
            out.to_str().unwrap(),
        ])
    };
    let (code, _, err) = run("-5,20,5,0", "hfs");
    assert_eq!(code, 2);
    assert!(err.contains("inside obstacle 0"), "{err}");
    let (code, _, err) = run("0,0,-0.5,0", "hfs");
    assert_eq!(code, 2);
    assert!(err.contains("under the ground"), "{err}");
    for bad in ["1,2,3", "a,b,c,d", "1,2,inf,0"] {
        let (code, _, err) = run(bad, "hfs");
        assert_eq!(code, 2, "{bad}");
        assert!(err.contains("--pose") && !err.contains("panicked"), "{err}");
    }
    let (code, _, err) = run("0,0,5,0", "kinect");
    assert_eq!(code, 2);
    assert!(err.contains("possible values: hfs, 2019, d455"), "{err}");
    assert!(!out.exists(), "no output on error");
}

#[test]
fn simulate_reports_json_and_writes_files() {
    let (dir, test) = test_file(2, valid_pair());
    let traj = dir.path().join("t.csv");
    let plot = dir.path().join("p.svg");
    let (code, out, err) = prgenuav(&[
        "simulate",
        test.to_str().unwrap(),
        "--json",
        "--trajectory",
        traj.to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for k in [
        "min_distance",
        "min_distance_raw",
        "per_obstacle",
        "status",
        "flight_time_s",
        "cycles",
        "wall_ms",
    ] {
        assert!(v.get(k).is_some(), "missing {k}: {out}");
    }
    assert_eq!(v["status"], "landed");
    assert_eq!(v["per_obstacle"].as_array().unwrap().len(), 2);
    let d = v["min_distance"].as_f64().unwrap();
    assert!(d > 0.0 && d < 15.0, "{d}");
    // The trajectory CSV reproduces the reported distance through `distance`.
    let (code, out2, _) = prgenuav(&["distance", test.to_str().unwrap(), traj.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0);
    let w: serde_json::Value = serde_json::from_str(&out2).unwrap();
    assert!((w["min_distance"].as_f64().unwrap() - d).abs() < 1e-3, "{out2}");
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("closest approach"));
}

#[test]
fn simulate_rejects_invalid_tests_like_check() {
    // Overlapping boxes break a rule: with --strict, same violations as `check`, exit 1; without, a warning
    // naming the rule (old editions' tests are re-flown and re-simulated).
    let overlapping = vec![
        Obstacle::new(10.0, 4.0, 20.0, -5.0, 20.0, 0.0),
        Obstacle::new(10.0, 4.0, 20.0, -6.0, 21.0, 0.0),
    ];
    let (_d, test) = test_file(2, overlapping);
    let (code_c, out_c, _) = prgenuav(&["check", test.to_str().unwrap()]);
    let (code_s, _, err_s) = prgenuav(&["simulate", test.to_str().unwrap(), "--strict"]);
    assert_eq!((code_c, code_s), (1, 1));
    let first_violation = out_c.lines().nth(1).unwrap().trim();
    assert!(err_s.contains(first_violation), "{err_s} vs {out_c}");
    let (code_w, _, err_w) = prgenuav(&["simulate", test.to_str().unwrap()]);
    assert_eq!(code_w, 0, "{err_w}");
    assert!(err_w.contains("warning") && err_w.contains("overlap"), "{err_w}");
    // Unreadable input: exit 2 with the loader's message.
    let (_d2, bad) = temp_file("bad.yaml", b"drone: [1,\n");
    let (code, _, err) = prgenuav(&["simulate", bad.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("bad.yaml") && !err.contains("panicked"), "{err}");
    let (code, _, err) = prgenuav(&["simulate", "missions/mission2.yaml", "--motion", "teleport"]);
    assert_eq!(code, 2);
    assert!(err.contains("possible values: px4, paper"), "{err}");
}

#[test]
fn fidelity_over_a_few_flights() {
    let dir = tempfile::tempdir().unwrap();
    for f in [
        "case_sefbk_001.json",
        "case_zhekai_002.json",
        "case_gulicatta_001.json",
        "case_casestudy_002.json",
    ] {
        std::fs::copy(repo().join("tests/data/hfs-flights").join(f), dir.path().join(f)).unwrap();
    }
    let (code, out, err) = prgenuav(&["fidelity", dir.path().to_str().unwrap(), "--json", "--jobs", "2"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let cases = v["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 3, "the obstacle-free case study is skipped");
    assert_eq!(v["skipped"][0], "case_casestudy_002.json");
    for c in cases {
        assert!(c["predicted"].as_f64().is_some() && c["real"].as_f64().is_some(), "{c}");
    }
    let mae = cases.iter().map(|c| c["abs_error"].as_f64().unwrap()).sum::<f64>() / 3.0;
    assert!((v["mae"].as_f64().unwrap() - mae).abs() < 1e-9);
    for k in ["spearman", "precision", "recall", "tiers"] {
        assert!(v.get(k).is_some(), "{k}");
    }
    assert_eq!(v["tiers"]["B"]["n"], 1);

    // Cross-validated: each held-out flight predicted with constants chosen on the others.
    let (code, out, err) = prgenuav(&[
        "fidelity",
        dir.path().to_str().unwrap(),
        "--cv",
        "2",
        "--motion",
        "px4",
        "--json",
        "--jobs",
        "2",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["k"], 2);
    assert_eq!(v["cross_validated"]["n"], 3);
    assert_eq!(v["in_sample"]["n"], 3);
    assert_eq!(v["grid"].as_array().map(Vec::len), Some(6));
    let folds = v["folds"].as_array().unwrap();
    assert_eq!(folds.iter().map(|f| f["n_held_out"].as_u64().unwrap()).sum::<u64>(), 3);
    assert_eq!(
        v["leave_one_tier_out"].as_array().map(Vec::len),
        Some(3),
        "tiers A, B, C"
    );
    // Too many folds for three obstacle sets, or a seed without --cv: clear errors.
    let (code, _, err) = prgenuav(&["fidelity", dir.path().to_str().unwrap(), "--cv", "4"]);
    assert_eq!(code, 2);
    assert!(err.contains("--cv 4") && err.contains("3 in"), "{err}");
    let (code, _, err) = prgenuav(&["fidelity", dir.path().to_str().unwrap(), "--cv-seed", "3"]);
    assert_eq!(code, 2);
    assert!(err.contains("--cv"), "{err}");
}

#[test]
fn fidelity_bad_input() {
    let empty = tempfile::tempdir().unwrap();
    let (code, _, err) = prgenuav(&["fidelity", empty.path().to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("no flight JSON"), "{err}");
    let (code, _, err) = prgenuav(&["fidelity", "/nonexistent/flights"]);
    assert_eq!(code, 2);
    assert!(!err.contains("panicked"), "{err}");
    let (_d, bad) = temp_file("broken.json", b"{\"id\": 1");
    let (code, _, err) = prgenuav(&["fidelity", bad.parent().unwrap().to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("broken.json") && err.contains("not JSON"), "{err}");
}
