//! Conformance on PX4 v1.17 (ignored by default; CI does not run it): missions 1-3 on a v1.17.x SITL build the
//! user made. Offboard and mission land and are judged right; avoidance is refused before anything is
//! uploaded or armed; `collision-prevention` lands or holds behind a box, and is judged.
//!
//! `PX4_SITL_BIN_V117=/path/to/v1.17/build/px4_sitl_default/bin/px4 cargo test -- --ignored px4_v117
//! --nocapture --test-threads=1`

use std::path::PathBuf;

use super::px4_release::{claimed, collision_prevention, release_bin};
use super::px4_sitl::all_modes;

fn v117() -> PathBuf {
    release_bin("PX4_SITL_BIN_V117", 17)
}

async fn modes(mission: u32) {
    let bin = v117();
    let slot = claimed();
    all_modes(&bin, slot.instance(), mission).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V117 (PX4 v1.17 SITL); run with --ignored px4_v117"]
async fn px4_v117_mission_1_all_modes() {
    modes(1).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V117 (PX4 v1.17 SITL); run with --ignored px4_v117"]
async fn px4_v117_mission_2_all_modes() {
    modes(2).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V117 (PX4 v1.17 SITL); run with --ignored px4_v117"]
async fn px4_v117_mission_3_all_modes() {
    modes(3).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V117 (PX4 v1.17 SITL); run with --ignored px4_v117"]
async fn px4_v117_mission_1_collision_prevention() {
    collision_prevention(&v117(), 1).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V117 (PX4 v1.17 SITL); run with --ignored px4_v117"]
async fn px4_v117_mission_2_collision_prevention() {
    collision_prevention(&v117(), 2).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "needs PX4_SITL_BIN_V117 (PX4 v1.17 SITL); run with --ignored px4_v117"]
async fn px4_v117_mission_3_collision_prevention() {
    collision_prevention(&v117(), 3).await;
}
