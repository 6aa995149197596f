//! One fidelity evaluation with hand-set model constants, overall, per tier and on two fixed halves of the
//! recorded flights (for honest fit-on-one-half, check-on-the-other numbers).
//!
//! `cargo run --release --example fid_explore -- paper|px4 [key=value ...]`, keys: `speed`, `yaw`, `frac`
//! (paper), `gain`, `vmax`, `acc`, `jerk` (px4; `jerk` > 0 selects the jerk-limited tracker), `tilt_tau`,
//! `tilt_drag` (enable the camera pitch model), `delay` (control delay, ticks), `shift` (move every obstacle
//! North, metres: a chance perturbation), `c_mission` (a flight file whose mission the tier-C flights fly
//! instead of their inferred one), `camera` (preset), `cruise` (MPC_XY_CRUISE on every flight), `jobs`, `dump`
//! (write the per-case JSON).
//! Halves: `prgenuav::lfs::fidelity::split_half` (a hash of the repeat group or id). Not a test: it takes a
//! minute per evaluation.

use std::path::Path;

use prgenuav::lfs::attitude::TiltParams;
use prgenuav::lfs::camera::Camera;
use prgenuav::lfs::fidelity::{Aggregates, FidelityReport, aggregate, aggregate_half, evaluate, load_dir, load_flight};
use prgenuav::lfs::motion::{PaperParams, Px4Params};
use prgenuav::lfs::sim::{MotionModel, SimConfig};

fn f(v: Option<f64>) -> String {
    v.map_or("  -  ".into(), |v| format!("{v:.3}"))
}

fn line(label: &str, a: &Aggregates) -> String {
    format!(
        "{label}: n {} MAE {} rho {} P {} R {}",
        a.n,
        f(a.mae),
        f(a.spearman),
        f(a.precision),
        f(a.recall)
    )
}

fn main() {
    let mut args = std::env::args().skip(1);
    let model = args.next().unwrap_or_else(|| "paper".into());
    let mut paper = PaperParams::default();
    let mut px4 = Px4Params::default();
    let mut tilt_params = TiltParams::default();
    let mut tilt_on = false;
    let mut camera = Camera::hfs();
    let mut jobs = 2;
    let mut shift = 0.0;
    let mut c_mission: Option<String> = None;
    let mut dump: Option<String> = None;
    let mut cruise: Option<f64> = None;
    for kv in args {
        let Some((k, v)) = kv.split_once('=') else {
            eprintln!("error: expected key=value, got {kv:?}");
            std::process::exit(2);
        };
        let x: f64 = v.parse().unwrap_or(f64::NAN);
        tilt_on |= k.starts_with("tilt");
        let t = &mut tilt_params;
        match k {
            "speed" => paper.max_speed_m_s = x,
            "yaw" => {
                paper.max_yaw_rate_deg_s = x;
                px4.max_yaw_rate_deg_s = x;
            }
            "frac" => paper.full_speed_yaw_fraction = x,
            "gain" => px4.pos_gain_per_s = x,
            "vmax" => px4.max_speed_xy_m_s = x,
            "acc" => px4.max_acc_m_s2 = x,
            "jerk" => px4.max_jerk_m_s3 = (x > 0.0).then_some(x),
            "tilt_tau" => t.time_constant_s = x,
            "tilt_drag" => t.drag_per_s = x,
            "camera" => camera = Camera::preset(v).unwrap_or_else(Camera::hfs),
            "shift" => shift = x,
            "c_mission" => c_mission = Some(v.to_string()),
            "delay" => {
                let d = v.parse().unwrap_or(0);
                paper.delay_ticks = d;
                px4.delay_ticks = d;
            }
            "jobs" => jobs = v.parse().unwrap_or(2),
            "dump" => dump = Some(v.to_string()),
            "cruise" => cruise = Some(x),
            _ => {
                eprintln!("error: unknown key {k}");
                std::process::exit(2);
            }
        }
    }
    let tilt = tilt_on.then_some(tilt_params);
    let motion = match model.as_str() {
        "paper" => MotionModel::Paper(paper),
        "px4" => MotionModel::Px4(px4),
        other => {
            eprintln!("error: unknown model {other:?}");
            std::process::exit(2);
        }
    };
    let (mut cases, skipped) = match load_dir(Path::new("tests/data/hfs-flights")) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    // `shift` moves every obstacle North by that many metres: a perturbation far below anything physical, to
    // see how much the metrics move by chance.
    for c in &mut cases {
        for o in &mut c.obstacles {
            o.position.x += shift;
        }
        // `cruise`: MPC_XY_CRUISE on every flight (the planner's cruise speed and lead, as the bench sets it).
        if let Some(v) = cruise {
            prgenuav::model::Param::set(&mut c.params, "MPC_XY_CRUISE", v);
        }
    }
    // `c_mission` flies the tier-C flights (whose mission was inferred) on the mission of another flight file.
    if let Some(path) = &c_mission {
        match load_flight(Path::new(path)) {
            Ok(Some(other)) => {
                for c in cases.iter_mut().filter(|c| c.tier == "C") {
                    c.mission = other.mission.clone();
                }
            }
            _ => {
                eprintln!("error: {path}: not a usable flight");
                std::process::exit(2);
            }
        }
    }
    let config = SimConfig {
        motion,
        camera,
        tilt,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let r: FidelityReport = evaluate(&cases, skipped, &config, jobs);
    let mut out = vec![line("all", &aggregate(&pairs(&r, |_| true)))];
    for t in r.tiers.keys() {
        out.push(line(t, &aggregate(&pairs(&r, |c| &c.tier == t))));
    }
    for h in 0..2 {
        out.push(line(&format!("half{h}"), &aggregate_half(&r, &cases, h)));
    }
    println!(
        "{} {:?} tilt {:?} ({:.0} s)",
        model,
        config.motion,
        tilt,
        t0.elapsed().as_secs_f64()
    );
    println!("  {}", out.join("\n  "));
    if let Some(path) = dump {
        match serde_json::to_string_pretty(&r) {
            Ok(s) => {
                if let Err(e) = std::fs::write(&path, s) {
                    eprintln!("error: {path}: {e}");
                }
            }
            Err(e) => eprintln!("error: {e}"),
        }
    }
}

fn pairs(r: &FidelityReport, keep: impl Fn(&prgenuav::lfs::fidelity::CaseResult) -> bool) -> Vec<(f64, f64)> {
    r.cases
        .iter()
        .filter(|c| keep(c))
        .filter_map(|c| c.predicted.map(|p| (p, c.real)))
        .collect()
}
