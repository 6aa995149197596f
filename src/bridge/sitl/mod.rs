//! Starting a PX4 SITL binary the user built (PX4 v1.12 to v1.17, headless) for tests and reference runs:
//! with its own SIH quadrotor (v1.14 on), or in external-simulator mode for prgenuav's iris simulator
//! ([`super::hil`]). Nothing here builds PX4: it runs `BUILD/bin/px4` with its `BUILD/etc` the way PX4's own
//! `make px4_sitl sihsim_quadx` (or `none_iris`) target does, in a private working directory, and stops it
//! when dropped (`spawn`: also when prgenuav is killed). `build` checks the user's build folder.

mod build;
mod console;
mod error;
pub mod slot;
mod spawn;
mod workdir;

use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

pub use build::{ModeUnsupported, NotABuild, Px4Build, VERSION_HEADER};
use console::{CONSOLE_LINES, Console};
pub use error::SitlError;
pub(crate) use spawn::{stop as kill_group, tie_to_parent};

use crate::bridge::options::VehicleSim;
use crate::bridge::px4_version::{ExternalSim, HomeUnits};
use crate::model::{GeoPoint, SIM_HOME};

/// How long the startup script may take before [`Px4Sitl::start`] gives up (a loaded machine boots PX4 in
/// 5-15 s).
pub const BOOT_TIMEOUT: Duration = Duration::from_secs(60);

/// The competition's home (PX4 1.14's SIH reads these integer parameters in 1e-7 degrees).
pub const COMPETITION_HOME_E7: (i64, i64) = (473_977_420, 85_455_940);

/// What simulates the vehicle of an instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SitlSim {
    /// PX4's own SIH quadrotor, reading its home from the environment in these units.
    Sih(HomeUnits),
    /// An external simulator PX4 connects to on TCP `4560 + instance`, started this way.
    External(ExternalSim),
}

/// What to start.
#[derive(Debug, Clone)]
pub struct SitlSpec {
    /// `BUILD/bin/px4` of a `px4_sitl_default` build.
    pub bin: PathBuf,
    /// Instance number: MAVLink system id `instance + 1`, API link sending to UDP `14540 + instance`.
    pub instance: u8,
    /// `PX4_SIM_SPEED_FACTOR` (SIH's lockstep speed-up; an external simulator sets its own pace).
    pub speed_factor: f64,
    /// Home (WGS-84 degrees, metres AMSL).
    pub home: GeoPoint,
    /// What simulates the vehicle.
    pub sim: SitlSim,
    /// How long the startup script may take.
    pub boot_timeout: Duration,
}

impl SitlSpec {
    /// The competition's home at `speed_factor`, written the way PX4 v1.14 reads it.
    pub fn new(bin: impl Into<PathBuf>, instance: u8, speed_factor: f64) -> Self {
        SitlSpec {
            bin: bin.into(),
            instance,
            speed_factor,
            home: SIM_HOME,
            sim: SitlSim::Sih(HomeUnits::IntE7),
            boot_timeout: BOOT_TIMEOUT,
        }
    }

    /// [`Self::new`] for a checked build: its `bin/px4`, its release's SIH home units.
    pub fn for_build(build: &Px4Build, instance: u8, speed_factor: f64) -> Self {
        Self::with_sim(build, instance, speed_factor, VehicleSim::Sih)
    }

    /// [`Self::new`] for a checked build flown with `sim`: SIH in its release's home units, or the
    /// release's external-simulator start-up (whether the build can is [`Px4Build::check_sim`]'s to say).
    pub fn with_sim(build: &Px4Build, instance: u8, speed_factor: f64, sim: VehicleSim) -> Self {
        let sim = match (sim, build.release.sih) {
            (VehicleSim::Sih, Some(units)) => SitlSim::Sih(units),
            _ => SitlSim::External(build.release.external),
        };
        SitlSpec {
            sim,
            ..Self::new(build.bin(), instance, speed_factor)
        }
    }

    /// The same at `home` (a test's home, so the test's frame and PX4's local origin coincide).
    pub fn at(mut self, home: GeoPoint) -> Self {
        self.home = home;
        self
    }

    /// `PX4_HOME_*` as this build's SIH start-up script reads them (none for an external simulator, whose
    /// GPS says where the vehicle is).
    pub fn home_env(&self) -> Vec<(&'static str, String)> {
        let SitlSim::Sih(units) = self.sim else {
            return Vec::new();
        };
        match units {
            HomeUnits::IntE7 => {
                let (lat, lon) = home_e7(self.home);
                vec![("PX4_HOME_LAT", lat.to_string()), ("PX4_HOME_LON", lon.to_string())]
            }
            HomeUnits::FloatDegrees => vec![
                ("PX4_HOME_LAT", format!("{:.7}", self.home.lat_deg)),
                ("PX4_HOME_LON", format!("{:.7}", self.home.lon_deg)),
                ("PX4_HOME_ALT", format!("{:.2}", self.home.alt_m)),
            ],
        }
    }
}

/// `home`'s latitude and longitude in the integer 1e-7 degrees PX4 1.14 and 1.15's SIH read from
/// `PX4_HOME_LAT` and `PX4_HOME_LON` (they ignore `PX4_HOME_ALT`: SIH's ground is its `SIH_LOC_H0`; heights
/// are judged above the ground, so the altitude does not matter).
pub fn home_e7(home: GeoPoint) -> (i64, i64) {
    ((home.lat_deg * 1e7).round() as i64, (home.lon_deg * 1e7).round() as i64)
}

/// One running instance; its process group killed (and its working directory removed) when dropped.
#[derive(Debug)]
pub struct Px4Sitl {
    child: Child,
    instance: u8,
    dir: PathBuf,
    console: Console,
}

impl Px4Sitl {
    /// Starts the instance and waits (bounded) until its startup script ran, so a flight does not race the boot.
    pub fn start(spec: &SitlSpec) -> Result<Px4Sitl, SitlError> {
        Self::start_until(spec, &AtomicBool::new(false))
    }

    /// [`Self::start`], giving up as soon as `stop` is raised.
    ///
    /// On Linux the instance is killed when the calling *thread* ends (PR_SET_PDEATHSIG): start it on a thread
    /// that outlives it (not a pool thread that may retire while it flies).
    pub fn start_until(spec: &SitlSpec, stop: &AtomicBool) -> Result<Px4Sitl, SitlError> {
        let etc = etc_dir(&spec.bin);
        if !etc.is_dir() {
            return Err(SitlError::NoEtc {
                bin: spec.bin.display().to_string(),
                etc: etc.display().to_string(),
            });
        }
        let spawn_err = |source| SitlError::Spawn {
            bin: spec.bin.display().to_string(),
            source,
        };
        let dir = workdir::create(spec.instance).map_err(spawn_err)?;
        let mut child = match spawn::command(spec, &etc, &dir).spawn() {
            Ok(c) => c,
            Err(e) => {
                let _ = std::fs::remove_dir_all(&dir);
                return Err(spawn_err(e));
            }
        };
        let (console, booted) = Console::follow(&mut child);
        let mut sitl = Px4Sitl {
            child,
            instance: spec.instance,
            dir,
            console,
        };
        sitl.wait_booted(spec, &booted, stop)?;
        Ok(sitl)
    }

    /// Waits until the console says the startup script ran, PX4 died, the boot timed out or `stop` rose.
    fn wait_booted(&mut self, spec: &SitlSpec, booted: &Receiver<()>, stop: &AtomicBool) -> Result<(), SitlError> {
        let deadline = Instant::now() + spec.boot_timeout;
        loop {
            if stop.load(Ordering::Relaxed) {
                return Err(SitlError::Cancelled {
                    instance: spec.instance,
                });
            }
            let left = deadline.saturating_duration_since(Instant::now());
            match booted.recv_timeout(left.min(Duration::from_millis(100))) {
                Ok(()) => return Ok(()),
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(SitlError::Died {
                        instance: spec.instance,
                        status: self.exit_status(Duration::from_secs(2)),
                        tail: self.console_tail(CONSOLE_LINES),
                    });
                }
                Err(RecvTimeoutError::Timeout) if left.is_zero() => {
                    return Err(SitlError::Boot {
                        instance: spec.instance,
                        secs: spec.boot_timeout.as_secs(),
                        tail: self.console_tail(CONSOLE_LINES),
                    });
                }
                Err(RecvTimeoutError::Timeout) => {}
            }
        }
    }

    /// The bridge's address for this instance's API link.
    pub fn url(&self) -> String {
        format!("udpin:0.0.0.0:{}", 14540 + u16::from(self.instance))
    }

    /// The instance number.
    pub fn instance(&self) -> u8 {
        self.instance
    }

    /// PX4's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// How PX4 ended, in words, if it has (it should run until dropped).
    pub fn exited(&mut self) -> Option<String> {
        self.child.try_wait().ok().flatten().map(|s| s.to_string())
    }

    /// The exit status once the process ends, waiting at most `wait` (its stdout may close a moment before).
    fn exit_status(&mut self, wait: Duration) -> String {
        let deadline = Instant::now() + wait;
        loop {
            if let Some(s) = self.exited() {
                return s;
            }
            if Instant::now() >= deadline {
                return "closed its console, still running".into();
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The instance's working folder (its `rootfs`: parameters, mission, `log/`).
    pub fn work_dir(&self) -> &Path {
        &self.dir
    }

    /// The ULog files PX4 wrote so far (under `log/`, one per arming), oldest first by name.
    pub fn ulogs(&self) -> Vec<PathBuf> {
        let mut found = Vec::new();
        collect_ulogs(&self.dir.join("log"), 3, &mut found);
        found.sort();
        found
    }

    /// The console's last `n` lines (at most `CONSOLE_LINES`), oldest first, terminal colours removed.
    pub fn console_tail(&self, n: usize) -> Vec<String> {
        self.console.tail(n)
    }
}

/// `.ulg` files under `dir`, at most `depth` folders down (PX4 writes `log/DATE/TIME.ulg`).
fn collect_ulogs(dir: &Path, depth: usize, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for p in entries.flatten().map(|e| e.path()) {
        if p.is_dir() && depth > 0 {
            collect_ulogs(&p, depth - 1, found);
        } else if p.extension().is_some_and(|x| x == "ulg") {
            found.push(p);
        }
    }
}

impl Drop for Px4Sitl {
    fn drop(&mut self) {
        spawn::stop(&mut self.child);
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// `BUILD/etc` for `BUILD/bin/px4`.
fn etc_dir(bin: &Path) -> PathBuf {
    bin.parent()
        .and_then(Path::parent)
        .map_or_else(|| PathBuf::from("etc"), |b| b.join("etc"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn etc_sits_beside_bin() {
        assert_eq!(
            etc_dir(Path::new("/b/px4_sitl_default/bin/px4")),
            PathBuf::from("/b/px4_sitl_default/etc")
        );
    }

    #[test]
    fn a_binary_without_etc_is_refused_with_the_path() {
        let err = Px4Sitl::start(&SitlSpec::new("/nonexistent/bin/px4", 0, 5.0)).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("/nonexistent/etc"), "{msg}");
    }

    #[test]
    fn the_home_is_written_in_integer_1e7_degrees() {
        assert_eq!(home_e7(crate::model::SIM_HOME), COMPETITION_HOME_E7);
        let south_west = GeoPoint {
            lat_deg: -33.868_820_04,
            lon_deg: -151.209_295_55,
            alt_m: 0.0,
        };
        assert_eq!(home_e7(south_west), (-338_688_200, -1_512_092_956));
    }

    #[test]
    fn v1_16_reads_its_home_in_float_degrees_with_the_altitude() {
        let home = GeoPoint {
            lat_deg: -33.868_820_04,
            lon_deg: 151.209_295_55,
            alt_m: 58.25,
        };
        let old = SitlSpec::new("/b/bin/px4", 0, 5.0).at(home);
        assert_eq!(
            old.home_env(),
            [
                ("PX4_HOME_LAT", "-338688200".to_string()),
                ("PX4_HOME_LON", "1512092956".to_string())
            ]
        );
        let new = SitlSpec {
            sim: SitlSim::Sih(HomeUnits::FloatDegrees),
            ..old.clone()
        };
        assert_eq!(
            new.home_env(),
            [
                ("PX4_HOME_LAT", "-33.8688200".to_string()),
                ("PX4_HOME_LON", "151.2092956".to_string()),
                ("PX4_HOME_ALT", "58.25".to_string())
            ]
        );
    }

    /// A fake `BUILD/bin/px4` running `script`, with `BUILD/etc`.
    #[cfg(unix)]
    fn fake(script: &str) -> (tempfile::TempDir, PathBuf) {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("bin")).unwrap();
        std::fs::create_dir_all(dir.path().join("etc")).unwrap();
        let bin = dir.path().join("bin/px4");
        std::fs::write(&bin, format!("#!/bin/sh\n{script}\n")).unwrap();
        std::fs::set_permissions(&bin, std::fs::Permissions::from_mode(0o755)).unwrap();
        (dir, bin)
    }

    #[cfg(unix)]
    #[test]
    fn a_px4_dying_at_boot_is_reported_with_its_last_words() {
        let (_d, bin) = fake("echo 'ERROR [simulator_sih] no sensors'\nexit 3");
        let err = Px4Sitl::start(&SitlSpec::new(&bin, 7, 5.0)).unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, SitlError::Died { instance: 7, .. }), "{msg}");
        assert!(msg.contains("exit status: 3") && msg.contains("no sensors"), "{msg}");
    }

    #[cfg(unix)]
    #[test]
    fn a_px4_that_never_boots_is_given_up_after_the_boot_timeout() {
        let (_d, bin) = fake("echo 'INFO  [init] starting'\nexec sleep 30");
        let spec = SitlSpec {
            boot_timeout: Duration::from_millis(300),
            ..SitlSpec::new(&bin, 8, 5.0)
        };
        let err = Px4Sitl::start(&spec).unwrap_err();
        assert!(matches!(err, SitlError::Boot { instance: 8, .. }), "{err}");
        assert!(err.to_string().contains("INFO  [init] starting"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn a_booted_instance_reports_its_death_and_its_logs() {
        let (_d, bin) = fake(
            "cd \"$5\" && mkdir -p log/2026-01-01 && : > log/2026-01-01/10_00_00.ulg\necho 'INFO  [init] Startup script returned successfully'\nsleep 1",
        );
        let mut px4 = Px4Sitl::start(&SitlSpec::new(&bin, 9, 5.0)).unwrap();
        assert_eq!(px4.url(), "udpin:0.0.0.0:14549");
        assert_eq!(px4.ulogs(), vec![px4.work_dir().join("log/2026-01-01/10_00_00.ulg")]);
        assert_eq!(px4.exited(), None, "still running right after its boot");
        assert!(px4.exit_status(Duration::from_secs(5)).contains("exit status: 0"));
        let dir = px4.work_dir().to_path_buf();
        drop(px4);
        assert!(!dir.exists(), "the working folder is removed with the instance");
    }

    #[test]
    fn a_raised_stop_flag_ends_the_boot_wait() {
        #[cfg(unix)]
        {
            let (_d, bin) = fake("exec sleep 30");
            let err = Px4Sitl::start_until(&SitlSpec::new(&bin, 6, 5.0), &AtomicBool::new(true)).unwrap_err();
            assert!(matches!(err, SitlError::Cancelled { instance: 6 }), "{err}");
        }
    }
}
