//! Integration tests: one binary, one module per area, shared helpers here.

mod anywhere;
mod bridge;
mod campaign;
mod campaign_folder;
mod cli_errors;
mod cp_campaign;
mod cp_flight;
mod documented;
mod evaluate;
mod evaluate_folder;
mod expected_2026;
mod flood;
mod frame;
mod generator;
mod geometry_props;
mod hitl_board;
mod hygiene;
mod identify;
mod journal;
mod journal_edits;
mod judge_props;
mod layering;
mod lfs;
mod missions;
mod pinned;
mod pinned_static;
mod pty;
mod px4_bench;
mod px4_campaign;
mod px4_cp;
mod px4_fake;
mod px4_iris;
mod px4_iris_fake;
mod px4_reference;
mod px4_release;
mod px4_repeated;
mod px4_sitl;
mod px4_v115;
mod px4_v116;
mod px4_v117;
mod px4_versions;
mod ready;
mod rules;
mod runner;
mod score;
mod score_input;
mod similarity_reference;
mod sizes;
mod slurm;
mod tcp_flood;
mod trust;
mod ulog;

use std::path::{Path, PathBuf};

use prgenuav::model::{Obstacle, TestCase};

/// The repository root (tests run with it as the working directory).
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A case study from `missions/`.
pub fn case(n: u32) -> TestCase {
    let path = repo().join(format!("missions/mission{n}.yaml"));
    TestCase::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The PX4 SITL binary a test flies (`PX4_SITL_BIN`, the user's own build's `bin/px4`). A test that needs it
/// fails without it, naming the variable: an ignored test run on purpose must check something.
pub fn px4_sitl_bin() -> PathBuf {
    match std::env::var_os("PX4_SITL_BIN") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => panic!(
            "this test flies PX4 SITL: set PX4_SITL_BIN=/path/to/PX4-Autopilot/build/px4_sitl_default/bin/px4 \
             (a PX4 SITL you built; docs/px4.md)"
        ),
    }
}

/// The build folder of [`px4_sitl_bin`] (`BUILD/bin/px4`).
pub fn px4_sitl_build() -> PathBuf {
    let bin = px4_sitl_bin();
    match bin.parent().and_then(Path::parent) {
        Some(build) => build.to_path_buf(),
        None => panic!("PX4_SITL_BIN={} is not BUILD/bin/px4", bin.display()),
    }
}

/// Runs the `prgenuav` binary in the repo root; returns (exit code, stdout, stderr).
pub fn prgenuav(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .args(args)
        .current_dir(repo())
        .output()
        .expect("run prgenuav");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Writes `text` to `name` in a fresh temp dir and returns the dir (kept alive by the caller) and the path.
pub fn temp_file(name: &str, text: &[u8]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join(name);
    std::fs::write(&path, text).expect("write temp file");
    (dir, path)
}

/// Two valid obstacles for mission 2 (a pair a human placed by hand, checked by `check`).
pub fn valid_pair() -> Vec<Obstacle> {
    vec![
        Obstacle::new(10.0, 2.0, 20.0, -5.0, 20.0, 30.0),
        Obstacle::new(12.0, 2.0, 20.0, -12.0, 32.0, 60.0),
    ]
}

/// A YAML of mission `n` with `obstacles`, written in a temp dir.
pub fn test_file(n: u32, obstacles: Vec<Obstacle>) -> (tempfile::TempDir, PathBuf) {
    let t = case(n).with_obstacles(obstacles);
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("test.yaml");
    t.save(&path, prgenuav::model::Spelling::Old).expect("save");
    (dir, path)
}

#[allow(dead_code)]
pub fn exists(p: &Path) -> bool {
    p.exists()
}
