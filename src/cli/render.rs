//! `prgenuav render TEST.yaml --pose X,Y,Z,YAW [--camera NAME] --out-file depth.npy [--points cloud.csv]`.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use geodesy::frames::{north_east_up_to_enu, yaw_ned_deg_to_enu_rad};
use nalgebra::Vector3;
use prgenuav::io::write_atomic;
use prgenuav::lfs::render::{CameraPose, Scene, cloud_from_depth, render_depth};

use super::values::CameraArg;

/// Arguments of `render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// The test YAML whose obstacles are rendered (with the ground plane).
    test: PathBuf,
    /// Vehicle pose `X,Y,Z,YAW`: X North and Y East in metres (local NED), Z height above ground in metres
    /// (positive up), YAW in degrees clockwise from North (as PX4).
    #[arg(long, allow_hyphen_values = true, value_name = "X,Y,Z,YAW")]
    pose: String,
    /// Camera preset.
    #[arg(long, value_enum, default_value_t = CameraArg::Hfs)]
    camera: CameraArg,
    /// The depth image to write: float32 NumPy .npy, shape (H, W), metres along the optical axis, NaN = no
    /// return.
    #[arg(long, value_name = "FILE.npy")]
    out_file: PathBuf,
    /// Also write the point cloud as CSV `x,y,z` in local NED metres (z down), as the planner receives it.
    #[arg(long, value_name = "FILE.csv")]
    points: Option<PathBuf>,
}

fn parse_pose(s: &str) -> anyhow::Result<[f64; 4]> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 4 {
        bail!("--pose must be X,Y,Z,YAW (4 numbers), got {s:?}");
    }
    let mut v = [0.0; 4];
    for (k, p) in parts.iter().enumerate() {
        v[k] = p
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .with_context(|| format!("--pose: {p:?} is not a finite number"))?;
    }
    Ok(v)
}

pub fn run(args: RenderArgs) -> anyhow::Result<ExitCode> {
    let [x, y, z, yaw_deg] = parse_pose(&args.pose)?;
    super::check_outputs(&[
        ("--out-file", Some(args.out_file.as_path())),
        ("--points", args.points.as_deref()),
    ])?;
    let camera = args.camera.model();
    let Some(test) = super::load_valid_test(&args.test)? else {
        return Ok(ExitCode::from(super::EXIT_FAIL));
    };
    let pose = CameraPose::level(north_east_up_to_enu(x, y, z), yaw_ned_deg_to_enu_rad(yaw_deg));
    let scene = Scene::new(&test.obstacles);
    let depth = render_depth(&scene, &camera, &pose).with_context(|| format!("cannot render pose {}", args.pose))?;
    write_atomic(&args.out_file, &depth.to_npy()).with_context(|| format!("writing {}", args.out_file.display()))?;
    let valid = depth.data.iter().filter(|d| d.is_finite()).count();
    if let Some(path) = &args.points {
        let cloud = cloud_from_depth(&camera, &pose, &depth);
        let mut csv = String::from("x,y,z\n");
        for p in &cloud {
            // ENU (x East, y North, z Up) to local NED.
            let ned = Vector3::new(p.y, p.x, -p.z);
            let _ = writeln!(csv, "{:.4},{:.4},{:.4}", ned.x, ned.y, ned.z);
        }
        write_atomic(path, csv.as_bytes()).with_context(|| format!("writing {}", path.display()))?;
        println!("{}: {} points", path.display(), cloud.len());
    }
    println!(
        "{}: {} x {} depth image ({} camera), {} pixels with a return",
        args.out_file.display(),
        camera.width_px,
        camera.height_px,
        camera.name,
        valid
    );
    Ok(ExitCode::SUCCESS)
}
