//! PX4 SITL instances prgenuav starts itself (`--px4 BUILD`): every flight on a fresh instance at the test's
//! home, so no flight inherits another's state (a reused PX4 1.14 SIH instance can stop arming: "Preflight
//! Fail: horizontal velocity unstable"), in the instance slot its vehicle owns; simulated by PX4's SIH or
//! by prgenuav's iris simulator ([`super::px4_iris`]).
//!
//! A PX4 that never boots, dies or cannot be flown is the backend's fault, not the test's: the flight is
//! retried once on a fresh instance and, if that fails too, journaled as [`crate::campaign::ground::flight_status::FlightStatus::BackendFailed`] (not charged).

use crate::campaign::ground::flight_status::FlightStatus;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use tokio::runtime::Handle;

use crate::bridge::companion::answers::AnswerCounts;
use crate::bridge::sitl::slot::{self, Slot};
use crate::bridge::sitl::{BOOT_TIMEOUT, Px4Build, Px4Sitl, SitlError, SitlSpec};
use crate::bridge::{Bench, BridgeError, FlightReport, FlyMode, FlyOptions, SimLink, VehicleSim};
use crate::campaign::fly::mock_mavlink::{flown, fly_blocking};
use crate::campaign::fly::px4_leaves::{
    console_note, keep_ulog, pointing_to_console, stopped_before_flying, write_log,
};
use crate::campaign::fly::retry::{Attempt, Retry, Tried};
use crate::campaign::fly::vehicle::{Flown, Vehicle, VehicleError};
use crate::judge::Judge;
use crate::model::TestCase;

/// Instances on one machine: instance `i` listens for the bridge on UDP `14540 + i`, and instance 10's port
/// would be 14550, where every instance's GCS link sends (QGroundControl's port).
pub const MAX_INSTANCES: usize = slot::SLOTS as usize;

/// `PX4_SIM_SPEED_FACTOR` when `--speed-factor` is not given (the factor the PX4 campaigns of
/// docs/experiments.md flew at).
pub const DEFAULT_SPEED_FACTOR: f64 = 5.0;

/// Real time one core carries of a flying SIH instance and its avoidance companion: an instance at speed
/// factor F needs about F / this many cores (measured in docs/px4.md).
pub const SIH_RTF_PER_CORE: f64 = 5.0;

/// The instance numbers of `k` vehicles: `0..k`, one slot each, so no two live instances share one.
pub fn instance_slots(k: usize) -> Result<Vec<u8>, String> {
    if k == 0 {
        return Err("--instances must be at least 1".into());
    }
    if k > MAX_INSTANCES {
        return Err(format!(
            "--instances {k}: at most {MAX_INSTANCES} PX4 instances on one machine (instance {MAX_INSTANCES} would \
             listen on UDP 14550, where every instance's GCS link sends)"
        ));
    }
    Ok((0..k).filter_map(|i| u8::try_from(i).ok()).collect())
}

/// The instances a machine with `cores` cores carries at `speed_factor`: `cores * SIH_RTF_PER_CORE /
/// speed_factor`, at least 1, at most [`MAX_INSTANCES`].
pub fn default_instances(cores: usize, speed_factor: f64) -> usize {
    let k = (cores as f64 * SIH_RTF_PER_CORE / speed_factor).floor();
    if k.is_finite() {
        (k as usize).clamp(1, MAX_INSTANCES)
    } else {
        1
    }
}

/// How every instance of a fleet is started and flown.
#[derive(Debug, Clone)]
pub struct Px4Settings {
    /// The user's build folder, checked.
    pub build: Px4Build,
    /// `PX4_SIM_SPEED_FACTOR`.
    pub speed_factor: f64,
    /// Copy PX4's ULog of each flight beside its trajectory (`candidate_N.ulg`).
    pub keep_ulog: bool,
    /// Obstacle mode.
    pub mode: FlyMode,
    /// Judge edition.
    pub judge: Judge,
    /// Re-anchor each test at the vehicle's home (the instance starts at the test's home anyway).
    pub anchor: bool,
    /// A flight is given up (LAND) after this many vehicle seconds.
    pub timeout_s: f64,
    /// How long PX4's startup script may take.
    pub boot_timeout: Duration,
    /// What simulates the vehicle.
    pub sim: VehicleSim,
    /// With the iris simulator: its link to PX4.
    pub sim_link: SimLink,
    /// What the flights reproduce (the iris's heading at rest, parameters over the test's).
    pub bench: Bench,
    /// The campaign's seed: with the iris simulator, each flight's sensor noise is drawn from it and the flight.
    pub seed: u64,
}

impl Px4Settings {
    /// Avoidance mode, the 2026 judge, PX4's boot bound, the bridge's flight timeout.
    pub fn new(build: Px4Build, speed_factor: f64) -> Self {
        Px4Settings {
            build,
            speed_factor,
            keep_ulog: false,
            mode: FlyMode::Avoidance,
            judge: Judge::default(),
            anchor: false,
            timeout_s: FlyOptions::default().timeout_s,
            boot_timeout: BOOT_TIMEOUT,
            sim: VehicleSim::Sih,
            sim_link: SimLink::Tcp,
            bench: Bench::Plain,
            seed: 0,
        }
    }

    /// The bridge's options for a flight on instance `instance` (reached at `connect`), recorded to `csv`.
    pub(super) fn fly_options(&self, connect: String, instance: u8, csv: &Path) -> FlyOptions {
        FlyOptions {
            connect,
            mode: self.mode,
            time_scale: self.speed_factor,
            // Under load an instance holds less than its speed factor: measured at connection.
            detect_time_scale: true,
            trajectory_csv: Some(csv.to_path_buf()),
            heartbeat_wait_s: 30.0,
            // Instance i is system i + 1: another vehicle heard on the port (a mock, a hand-started PX4) is not
            // flown by mistake.
            target_system: Some(instance.saturating_add(1)),
            judge: self.judge,
            anchor_at_vehicle_home: self.anchor,
            timeout_s: self.timeout_s,
            ..FlyOptions::default()
        }
    }
}

/// One instance slot: each flight on a fresh PX4 started there, stopped when the flight ends.
pub struct Px4Vehicle {
    handle: Handle,
    settings: Px4Settings,
    instance: u8,
    retry: Retry,
    /// The machine-wide claim on `instance` (none when the caller chose the instance).
    _slot: Option<Slot>,
}

impl Px4Vehicle {
    /// `k` vehicles on the `k` lowest instance slots free on this machine (claimed for the campaign, so another
    /// campaign or `fly --px4` job on the machine takes others).
    pub fn fleet(handle: &Handle, settings: &Px4Settings, k: usize) -> Result<Vec<Px4Vehicle>, String> {
        instance_slots(k)?;
        let slots = slot::claim_many_with(k, settings.sim).map_err(|e| e.to_string())?;
        Ok(slots
            .into_iter()
            .map(|s| Px4Vehicle::new(handle.clone(), settings.clone(), s.instance()).claimed(s))
            .collect())
    }

    fn claimed(mut self, slot: Slot) -> Self {
        self._slot = Some(slot);
        self
    }

    /// The vehicle of instance slot `instance`.
    pub fn new(handle: Handle, settings: Px4Settings, instance: u8) -> Self {
        Px4Vehicle {
            handle,
            settings,
            instance,
            retry: Retry::default(),
            _slot: None,
        }
    }

    /// A PX4 started on this vehicle's slot since it was claimed (by hand, say) would refuse the flight's PX4
    /// ("PX4 server already running"): the vehicle moves to the next free slot, saying so in `log`.
    fn leave_a_slot_taken_since(&mut self, log: &mut String) {
        if self._slot.is_none() || !slot::held_by_px4(self.instance) {
            return;
        }
        if let Ok(free) = slot::claim(0) {
            let _ = writeln!(
                log,
                "=== instance {} is held by a PX4 started since: flying on instance {} ===",
                self.instance,
                free.instance()
            );
            self.instance = free.instance();
            self._slot = Some(free);
        }
    }

    /// One fresh instance at the test's home, flown and stopped; its console appended to `log`.
    fn attempt(&self, test: &TestCase, csv: &Path, stop: &AtomicBool, log: &mut String) -> Attempt {
        if self.settings.sim == VehicleSim::Iris {
            return self.attempt_iris(test, csv, stop, log);
        }
        let s = &self.settings;
        let spec = SitlSpec {
            boot_timeout: s.boot_timeout,
            ..SitlSpec::for_build(&s.build, self.instance, s.speed_factor).at(test.home)
        };
        let mut px4 = match Px4Sitl::start_until(&spec, stop) {
            Ok(px4) => px4,
            Err(e) => return boot_failed(e, log),
        };
        let opts = s.fly_options(px4.url(), self.instance, csv);
        let result = fly_blocking(&self.handle, test, &opts, stop);
        let died = px4.exited();
        self.keep_console(&px4, csv, log);
        drop(px4);
        outcome(result, died, self.instance, None)
    }

    /// PX4's ULog (with `--keep-ulog`) beside the trajectory, and its console into `log`.
    pub(super) fn keep_console(&self, px4: &Px4Sitl, csv: &Path, log: &mut String) {
        if self.settings.keep_ulog {
            keep_ulog(px4, &csv.with_extension("ulg"), log);
        }
        push_lines(log, &px4.console_tail(usize::MAX));
    }

    /// The instance number.
    pub(super) fn instance(&self) -> u8 {
        self.instance
    }

    /// How every flight is started and flown.
    pub(super) fn settings(&self) -> &Px4Settings {
        &self.settings
    }

    /// The runtime flights are flown on.
    pub(super) fn handle(&self) -> &Handle {
        &self.handle
    }
}

/// A PX4 that did not boot: the campaign's stop, or a backend failure with its console's last words in `log`.
pub(super) fn boot_failed(e: SitlError, log: &mut String) -> Attempt {
    match e {
        SitlError::Cancelled { .. } => Attempt::Stopped,
        e => {
            if let SitlError::Boot { tail, .. } | SitlError::Died { tail, .. } = &e {
                push_lines(log, tail);
            }
            Attempt::Failed(e.to_string())
        }
    }
}

/// How a flight on a fresh instance came out: the flight, or why the backend (not the test) failed it: the
/// companion starved, PX4 died, the simulator lost PX4 (`simulator`), or PX4 was never ready.
pub(super) fn outcome(
    result: Result<FlightReport, BridgeError>,
    died: Option<String>,
    instance: u8,
    simulator: Option<String>,
) -> Attempt {
    match (result, died) {
        (Ok(r), _) if let Some(why) = starved(r.companion_answers, instance) => Attempt::Failed(why),
        (Ok(r), _) if r.status.completed() => Attempt::Flew(flown(r)),
        (_, Some(status)) => Attempt::Failed(format!("PX4 instance {instance} exited mid-flight ({status})")),
        (_, None) if let Some(why) = simulator => Attempt::Failed(format!(
            "prgenuav's simulator of PX4 instance {instance} stopped: {why}"
        )),
        (Err(e), None) => Attempt::Failed(format!("PX4 instance {instance}: {e}")),
        (Ok(r), None) => never_ready(flown(r), instance),
    }
}

/// A flight whose avoidance companion fell behind ([`AnswerCounts::starved`]) flew PX4's own setpoint
/// instead of avoiding: the machine's failure, not the test's, so it is retried like a silent instance.
fn starved(answers: Option<AnswerCounts>, instance: u8) -> Option<String> {
    let c = answers.filter(AnswerCounts::starved)?;
    Some(format!(
        "PX4 instance {instance}: {}: the machine did not keep up, so the flight did not test the avoidance",
        c.describe()
    ))
}

/// A fresh instance at the test's home that never became ready to arm (`rejected`), or that went silent while
/// still running (`link_lost`: a starved instance stops answering commands, even the arming one), failed on
/// PX4's side or the machine's, not on the test's: the flight is retried on a fresh instance like a failed
/// boot, and never charged to the budget.
fn never_ready(f: Flown, instance: u8) -> Attempt {
    let why = f.reason.as_deref().unwrap_or("no reason given");
    match f.status {
        FlightStatus::REJECTED => Attempt::Failed(format!("PX4 instance {instance} was never ready to fly: {why}")),
        FlightStatus::LINK_LOST => Attempt::Failed(format!("PX4 instance {instance} went silent: {why}")),
        _ => Attempt::Flew(f),
    }
}

impl Vehicle for Px4Vehicle {
    fn name(&self) -> String {
        let sim = match self.settings.sim {
            VehicleSim::Sih => "sih",
            VehicleSim::Iris => "iris",
        };
        format!("px4-{sim}#{}", self.instance)
    }

    fn fly(&mut self, test: &TestCase, csv: &Path, stop: &AtomicBool) -> Result<Flown, VehicleError> {
        let log_path = csv.with_extension("px4.log");
        let mut log = String::new();
        self.leave_a_slot_taken_since(&mut log);
        let mut retry = std::mem::take(&mut self.retry);
        let tried = retry.tries(stop, |n| {
            let _ = writeln!(log, "=== attempt {n}: PX4 instance {} ===", self.instance);
            match self.attempt(test, csv, stop, &mut log) {
                Attempt::Failed(_) if stop.load(Ordering::Relaxed) => Attempt::Stopped,
                other => other,
            }
        });
        self.retry = retry;
        let written = write_log(&log_path, &log);
        let failures = match tried {
            Tried::Flew(f) => return Ok(pointing_to_console(f, &written)),
            Tried::Stopped => return Ok(stopped_before_flying(&written)),
            Tried::Failed(failures) => failures,
        };
        let what = match failures.as_slice() {
            [a, b] if a == b => format!("PX4 failed the same way on two fresh instances: {a}"),
            [a, b] => format!("PX4 failed on two fresh instances: {a}; retry: {b}"),
            _ => format!("PX4 failed: {}", failures.join("; ")),
        };
        let reason = format!("{what}; {}", console_note(&written));
        self.retry.failed(self.name(), reason)
    }
}

pub(super) fn push_lines(log: &mut String, lines: &[String]) {
    for l in lines {
        log.push_str(l);
        log.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fresh_instance_that_never_arms_or_goes_silent_is_a_backend_failure_and_a_flown_one_is_not() {
        let f = |status: FlightStatus| {
            Flown::unflown(status, "not ready to arm within 60 s (missing: home position)".into())
        };
        match never_ready(f(FlightStatus::REJECTED), 3) {
            Attempt::Failed(why) => assert!(why.contains("instance 3") && why.contains("home position"), "{why}"),
            _ => panic!("a rejected flight on a fresh instance must be retried, not journaled as flown"),
        }
        let silent = Flown {
            reason: Some("arming: no answer from the vehicle after 10 retries".into()),
            ..f(FlightStatus::LINK_LOST)
        };
        match never_ready(silent, 1) {
            Attempt::Failed(why) => assert!(why.contains("went silent") && why.contains("arming"), "{why}"),
            _ => panic!("a fresh instance that stops answering must be retried, not charged as a flight"),
        }
        for status in [FlightStatus::LANDED, FlightStatus::COLLISION, FlightStatus::TIMEOUT] {
            assert!(matches!(never_ready(f(status), 0), Attempt::Flew(_)), "{status}");
        }
    }

    #[test]
    fn a_flight_whose_companion_fell_behind_is_a_backend_failure() {
        let answers = |planned, mirrored| Some(AnswerCounts { planned, mirrored });
        let why = starved(answers(1569, 146), 2).expect("9 % mirrored is starved");
        assert!(why.contains("instance 2") && why.contains("146 of 1715"), "{why}");
        assert_eq!(
            starved(answers(4400, 1), 2),
            None,
            "only the answer before the first plan"
        );
        assert_eq!(starved(None, 2), None, "no companion (Collision Prevention, mission)");
    }

    #[test]
    fn k_vehicles_own_k_distinct_slots() {
        assert_eq!(instance_slots(3).unwrap(), vec![0, 1, 2]);
        assert_eq!(instance_slots(MAX_INSTANCES).unwrap().len(), MAX_INSTANCES);
        assert!(instance_slots(0).unwrap_err().contains("at least 1"));
        let e = instance_slots(MAX_INSTANCES + 1).unwrap_err();
        assert!(e.contains("at most 10") && e.contains("14550"), "{e}");
    }

    #[test]
    fn the_default_fleet_follows_cores_and_speed() {
        assert_eq!(default_instances(2, SIH_RTF_PER_CORE * 2.0), 1);
        assert_eq!(default_instances(2, SIH_RTF_PER_CORE), 2);
        assert_eq!(default_instances(4, SIH_RTF_PER_CORE / 2.0), 8);
        assert_eq!(default_instances(1, 1000.0), 1, "at least one");
        assert_eq!(default_instances(64, 1.0), MAX_INSTANCES, "at most the slots there are");
        assert_eq!(default_instances(2, 0.0), 1, "a nonsense factor (refused earlier): one");
    }
}
