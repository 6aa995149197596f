//! The high-fidelity side of a campaign: the embedded mock autopilot (a fresh one per flight, so every flight
//! starts at home as in Aerialist) or MAVLink vehicles (PX4 SITL instances, flight controllers), flown with
//! the bridge.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use mock_autopilot::server::DEFAULT_LOCKSTEP_WAIT;
use mock_autopilot::{LinkSpec, MockAutopilot, SpeedFactor};
use tokio::runtime::Handle;

use crate::bridge::session::report::Status;
use crate::bridge::{BridgeError, CancelToken, FlightReport, FlyMode, FlyOptions, fly};
use crate::campaign::fly::retry::{Attempt, Retry, Tried};
use crate::campaign::fly::vehicle::{Flown, Vehicle, VehicleError};
use crate::campaign::ground::flight_status::FlightStatus;
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
    retry: Retry,
    faults: Option<mock_autopilot::link::Faults>,
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
            retry: Retry::default(),
            faults: None,
        }
    }

    /// Fly mocks whose link has `faults` (tests of what a failing link does to a campaign).
    pub fn with_faults(mut self, faults: mock_autopilot::link::Faults) -> Self {
        self.faults = Some(faults);
        self
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

impl MockVehicle {
    /// One try of a flight on a fresh mock. A flight that lost the link before the mock reported a single
    /// position (on a loaded machine: "uploading the mission: no answer") failed on the machine, not on the
    /// test: it is tried again like a PX4 that did not boot.
    fn attempt(&self, test: &TestCase, csv: &Path, stop: &AtomicBool) -> Result<Attempt, VehicleError> {
        let unreachable = |reason: String| VehicleError::Unreachable {
            vehicle: self.name.clone(),
            reason,
        };
        let addr = "127.0.0.1:0".parse().map_err(|e| unreachable(format!("{e}")))?;
        let mut builder = mock_builder_with(&self.profile, self.mode)
            .seed(flight_seed(self.seed, csv))
            .link(LinkSpec::UdpIn(addr))
            .speed_factor(SpeedFactor::Times(self.speed))
            .lockstep(self.lockstep.map(|_| DEFAULT_LOCKSTEP_WAIT));
        if let Some(f) = &self.faults {
            builder = builder.faults(f.clone());
        }
        let mock = self
            .handle
            .block_on(builder.spawn())
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
        Ok(match result {
            Ok(r) if r.status == Status::LinkLost && r.samples == 0 && !stop.load(Ordering::Relaxed) => {
                Attempt::Failed(format!(
                    "the embedded mock lost the link before its first position: {}",
                    r.reason.as_deref().unwrap_or("no reason given")
                ))
            }
            Ok(r) => Attempt::Flew(flown(r)),
            Err(e) => return Err(unreachable(e.to_string())),
        })
    }
}

impl Vehicle for MockVehicle {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn fly(&mut self, test: &TestCase, csv: &Path, stop: &AtomicBool) -> Result<Flown, VehicleError> {
        let mut retry = std::mem::take(&mut self.retry);
        let mut error = None;
        let tried = retry.tries(stop, |_| match self.attempt(test, csv, stop) {
            Ok(a) => a,
            Err(e) => {
                error = Some(e);
                Attempt::Stopped
            }
        });
        self.retry = retry;
        if let Some(e) = error {
            return Err(e);
        }
        match tried {
            Tried::Flew(f) => Ok(f),
            Tried::Stopped => Ok(Flown::unflown(
                FlightStatus::ABORTED,
                "stopped before the mock flew".into(),
            )),
            Tried::Failed(why) => {
                let reason = match why.as_slice() {
                    [a, b] if a == b => format!("{a} (on both tries)"),
                    _ => why.join("; retry: "),
                };
                self.retry.failed(self.name(), reason)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mock_that_loses_the_link_before_its_first_position_is_tried_again_then_failed_on_its_backend() {
        let rt = tokio::runtime::Runtime::new().unwrap();
        // Most messages lost, as on a loaded machine: the setup gets no answer after its retries.
        let faults = mock_autopilot::link::Faults {
            loss: 0.8,
            ..mock_autopilot::link::Faults::default()
        };
        let mut v = MockVehicle::new(rt.handle().clone(), 0, 20.0, FlyMode::Mission, None).with_faults(faults);
        let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("missions/mission2.yaml");
        let test = TestCase::load(&case).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let f = v
            .fly(&test, &dir.path().join("candidate_0.csv"), &AtomicBool::new(false))
            .unwrap();
        assert_eq!(f.status, FlightStatus::BackendFailed, "{f:?}");
        let why = f.reason.unwrap();
        assert!(
            why.contains("before its first position") && why.contains("no answer"),
            "{why}"
        );
        assert!(
            why.contains("both tries") || why.contains("; retry: "),
            "two tries: {why}"
        );
    }

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
