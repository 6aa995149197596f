//! Conformance on PX4 v1.16 (ignored by default; CI does not run it): missions 1-3 in every mode on a v1.16.x
//! SITL build the user made, `px4_sitl`'s checks. Offboard and mission must land and be judged right;
//! avoidance must be refused before anything is uploaded or armed.
//!
//! `PX4_SITL_BIN_V116=/path/to/v1.16/build/px4_sitl_default/bin/px4 cargo test --release -- --ignored px4_v116
//! --nocapture --test-threads=1`

use std::path::PathBuf;

use super::px4_release::release_bin;
use super::px4_sitl::all_modes;

/// `PX4_SITL_BIN_V116`, checked to be a v1.16 build (so the avoidance refusal is exercised).
fn v116() -> PathBuf {
    release_bin("PX4_SITL_BIN_V116", 16)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V116 (PX4 v1.16 SITL); run with --ignored px4_v116"]
async fn mission_1_all_modes() {
    all_modes(&v116(), 5, 1).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V116 (PX4 v1.16 SITL); run with --ignored px4_v116"]
async fn mission_2_all_modes() {
    all_modes(&v116(), 6, 2).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V116 (PX4 v1.16 SITL); run with --ignored px4_v116"]
async fn mission_3_all_modes() {
    all_modes(&v116(), 7, 3).await;
}
