//! Writes the simulated path of recorded flights next to the recorded one, to compare them by eye or by script.
//!
//! `cargo run --release --example fid_paths -- OUT_DIR paper|px4 [ID ...]` simulates the named flights of
//! `tests/data/hfs-flights` (all tier-A flights without IDs) and writes `OUT_DIR/ID.csv` with columns
//! `t_s,x,y,z` (Aerialist frame: x North, y East, z up, metres). Not a test.

use std::fmt::Write as _;
use std::path::Path;

use prgenuav::lfs::fidelity::load_dir;
use prgenuav::lfs::sim::{MotionModel, SimConfig, simulate_parts};

fn main() {
    let mut args = std::env::args().skip(1);
    let (Some(out), Some(model)) = (args.next(), args.next()) else {
        eprintln!("usage: fid_paths OUT_DIR paper|px4 [ID ...]");
        std::process::exit(2);
    };
    let Some(motion) = MotionModel::by_name(&model) else {
        eprintln!("error: unknown model {model:?}");
        std::process::exit(2);
    };
    let ids: Vec<String> = args.collect();
    let (cases, _) = match load_dir(Path::new("tests/data/hfs-flights")) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("error: {out}: {e}");
        std::process::exit(2);
    }
    let config = SimConfig {
        motion,
        ..Default::default()
    };
    for c in cases.iter().filter(|c| {
        if ids.is_empty() {
            c.tier == "A"
        } else {
            ids.contains(&c.id)
        }
    }) {
        let Ok(r) = simulate_parts(&c.mission, &c.obstacles, &c.params, &config) else {
            eprintln!("{}: cannot simulate", c.id);
            continue;
        };
        let mut s = String::from("t_s,x,y,z\n");
        for p in &r.trajectory.samples {
            let _ = writeln!(s, "{:.2},{:.3},{:.3},{:.3}", p.t_s, p.x, p.y, p.z);
        }
        let path = Path::new(&out).join(format!("{}.csv", c.id));
        if let Err(e) = std::fs::write(&path, s) {
            eprintln!("error: {}: {e}", path.display());
        }
        let d = r.distance.map_or(f64::NAN, |d| d.min_distance);
        println!("{} real {:.2} predicted {d:.2} {:?}", c.id, c.real_m, r.status);
    }
}
