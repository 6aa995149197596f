//! The high-fidelity side of a campaign: the embedded mock autopilot (a fresh one per flight, so every flight
//! starts at home as in Aerialist) or MAVLink vehicles (PX4 SITL instances, flight controllers), flown with
//! the bridge.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT;
use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
use tokio::runtime::Handle;

use crate::bridge::{BridgeError, CancelToken, FlightReport, FlyMode, FlyOptions, fly};
use crate::campaign::fly::vehicle::{Flown, Vehicle, VehicleError};
use crate::campaign::settings::mock_profile::MockProfile;
use crate::judge::Judge;
use crate::model::TestCase;

/// Flies with the bridge on `handle`'s runtime, turning the campaign's stop flag into a bridge cancel (the
/// flight then lands and keeps its recording).
pub(in crate::campaign) fn fly_blocking(
    handle: &Handle,
    test: &TestCase,
    opts: &FlyOptions,
    stop: &AtomicBool,
) -> Result<FlightReport, BridgeError> {
    handle.block_on(async {
        let token = CancelToken::new();
        let watch = token.clone();
        let watcher = async {
            while !stop.load(Ordering::Relaxed) {
                tokio::time::sleep(Duration::from_millis(100)).await;
            }
            watch.cancel();
            std::future::pending::<()>().await;
        };
        tokio::select! {
            r = fly(test, opts, token) => r,
            () = watcher => unreachable!("the watcher never finishes"),
        }
    })
}

pub(in crate::campaign) fn flown(report: FlightReport) -> Flown {
    Flown {
        min_distance: report.min_distance,
        min_distance_raw: report.min_distance_raw,
        flight_time_s: report.flight_time_s,
        warnings: report.warnings,
        reason: report.reason,
        ..Flown::ended(report.status.into())
    }
    .with_cp(report.collision_prevention)
}

/// A MAVLink vehicle at a fixed address.
pub struct LinkVehicle {
    handle: Handle,
    opts: FlyOptions,
}

impl LinkVehicle {
    /// A vehicle at `url` (rust-mavlink or MAVSDK address syntax), flown in `mode`, each flight given up after
    /// `timeout_s`. Its clock runs `time_scale` times real time, or, with `None`, as measured at each connection
    /// (a pool of simulators faster than real time).
    pub fn new(
        handle: Handle,
        url: &str,
        mode: FlyMode,
        heartbeat_wait_s: f64,
        time_scale: Option<f64>,
        timeout_s: f64,
    ) -> Self {
        let opts = FlyOptions {
            connect: url.to_string(),
            mode,
            heartbeat_wait_s,
            time_scale: time_scale.unwrap_or(1.0),
            detect_time_scale: time_scale.is_none(),
            timeout_s,
            ..FlyOptions::default()
        };
        Self { handle, opts }
    }

    /// Judge its flights by `judge`; re-anchor each test at the vehicle's home if `anchor`.
    pub fn judged(mut self, judge: Judge, anchor: bool) -> Self {
        self.opts.judge = judge;
        self.opts.anchor_at_vehicle_home = anchor;
        self
    }
}

impl Vehicle for LinkVehicle {
    fn name(&self) -> String {
        self.opts.connect.clone()
    }

    fn fly(&mut self, test: &TestCase, csv: &Path, stop: &AtomicBool) -> Result<Flown, VehicleError> {
        let opts = FlyOptions {
            trajectory_csv: Some(csv.to_path_buf()),
            ..self.opts.clone()
        };
        match fly_blocking(&self.handle, test, &opts, stop) {
            Ok(report) => Ok(flown(report)),
            Err(e) => Err(VehicleError::Unreachable {
                vehicle: self.name(),
                reason: e.to_string(),
            }),
        }
    }
}

/// The seed of the flight recorded in `trajectory_csv` of a campaign seeded with `seed` (the mock's gusts, the
/// iris simulator's sensor noise): its file name (FNV-1a) mixed with the seed.
pub(in crate::campaign) fn flight_seed(seed: u64, trajectory_csv: &Path) -> u64 {
    let name = trajectory_csv
        .file_name()
        .map(|n| n.as_encoded_bytes())
        .unwrap_or_default();
    mock_autopilot::gusts::flight_seed(seed, crate::io::fnv1a(name, 0))
}

/// The embedded mock autopilot, started afresh for every flight on an ephemeral loopback port.
pub struct MockVehicle {
    handle: Handle,
    name: String,
    speed: f64,
    mode: FlyMode,
    lockstep: Option<Duration>,
    judge: Judge,
    anchor: bool,
    timeout_s: f64,
    profile: MockProfile,
    seed: u64,
}

/// The embedded mock for `mode` with the default profile ([`crate::campaign::settings::mock_profile::DEFAULT_PROFILE`]).
pub fn mock_builder(mode: FlyMode) -> mock_autopilot::Builder {
    mock_builder_with(&MockProfile::default(), mode)
}

/// The embedded mock for `mode`: in avoidance mode (what the profiles are fitted to) `profile`, else PX4's
/// defaults.
pub fn mock_builder_with(profile: &MockProfile, mode: FlyMode) -> mock_autopilot::Builder {
    if mode == FlyMode::Avoidance {
        profile.builder()
    } else {
        MockAutopilot::builder()
    }
}

impl MockVehicle {
    /// Mock number `index`, its clock `speed` times faster than real time (at most, with `lockstep =
    /// Some(latency)`: the mock then holds its clock until each avoidance answer, planned on the pose
    /// `latency` old; see [`FlyOptions::lockstep`]).
    pub fn new(handle: Handle, index: usize, speed: f64, mode: FlyMode, lockstep: Option<Duration>) -> Self {
        Self {
            handle,
            name: format!("mock#{index}"),
            speed,
            mode,
            lockstep,
            judge: Judge::default(),
            anchor: false,
            timeout_s: FlyOptions::default().timeout_s,
            profile: MockProfile::default(),
            seed: 0,
        }
    }

    /// Draw each flight's gusts (the profile's flight-to-flight scatter) from the campaign's `seed` and the
    /// flight's trajectory file name (`flights/candidate_N_K.csv`: which test, which flight of it), so a
    /// campaign flies the same flights whichever vehicle takes them, in whatever order, and on resume.
    pub fn seeded(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Judge its flights by `judge`; re-anchor each test at the vehicle's home if `anchor`.
    pub fn judged(mut self, judge: Judge, anchor: bool) -> Self {
        self.judge = judge;
        self.anchor = anchor;
        self
    }

    /// Fly the mock with `profile` (default: [`MockProfile::default`]).
    pub fn with_profile(mut self, profile: MockProfile) -> Self {
        self.profile = profile;
        self
    }

    /// Each flight is given up (LAND) after `timeout_s` vehicle seconds.
    pub fn with_timeout(mut self, timeout_s: f64) -> Self {
        self.timeout_s = timeout_s;
        self
    }
}

impl Vehicle for MockVehicle {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn fly(&mut self, test: &TestCase, csv: &Path, stop: &AtomicBool) -> Result<Flown, VehicleError> {
        let unreachable = |reason: String| VehicleError::Unreachable {
            vehicle: self.name.clone(),
            reason,
        };
        let addr = "127.0.0.1:0".parse().map_err(|e| unreachable(format!("{e}")))?;
        let mock = self
            .handle
            .block_on(
                mock_builder_with(&self.profile, self.mode)
                    .seed(flight_seed(self.seed, csv))
                    .link(LinkSpec::UdpIn(addr))
                    .speed_factor(SpeedFactor::Times(self.speed))
                    .lockstep(self.lockstep.map(|_| DEFAULT_LOCKSTEP_WAIT))
                    .spawn(),
            )
            .map_err(|e| unreachable(e.to_string()))?;
        let port = mock
            .local_addr()
            .map(|a| a.port())
            .ok_or_else(|| unreachable("no local port".into()))?;
        let opts = FlyOptions {
            connect: format!("udpout:127.0.0.1:{port}"),
            mode: self.mode,
            time_scale: self.speed,
            trajectory_csv: Some(csv.to_path_buf()),
            heartbeat_wait_s: 20.0,
            lockstep: self.lockstep,
            judge: self.judge,
            anchor_at_vehicle_home: self.anchor,
            timeout_s: self.timeout_s,
            ..FlyOptions::default()
        };
        let result = fly_blocking(&self.handle, test, &opts, stop);
        // Stopping the mock cannot fail in a way that matters to the flight already recorded.
        let _ = self.handle.block_on(mock.shutdown());
        result.map(flown).map_err(|e| unreachable(e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_flight_of_a_campaign_has_its_own_seed_whatever_the_folder() {
        let s = |seed, p: &str| flight_seed(seed, Path::new(p));
        let names = [
            "flights/candidate_1.csv",
            "flights/candidate_1_2.csv",
            "flights/candidate_2.csv",
        ];
        let seeds: std::collections::BTreeSet<u64> = names.iter().map(|n| s(7, n)).collect();
        assert_eq!(seeds.len(), names.len());
        assert_eq!(
            s(7, "flights/candidate_1_2.csv"),
            s(7, "/tmp/other/flights/candidate_1_2.csv")
        );
        assert_ne!(s(7, "flights/candidate_1.csv"), s(8, "flights/candidate_1.csv"));
    }
}
