//! Starting a PX4 SITL binary the user built (PX4 v1.14, SIH quadrotor, headless) for tests and reference
//! runs. Nothing here builds PX4: it runs `BUILD/bin/px4` with its `BUILD/etc` the way PX4's own
//! `make px4_sitl sihsim_quadx` target does, in a private working directory, and stops it when dropped.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// How long the startup script may take before [`Px4Sitl::start`] gives up.
const BOOT_TIMEOUT: Duration = Duration::from_secs(60);

/// Console lines kept for [`Px4Sitl::console_tail`]: enough for a flight's failsafe, landing and disarm
/// messages, small enough to keep for every instance of a fleet.
const CONSOLE_LINES: usize = 400;

/// The competition's home (PX4 1.14's SIH reads these integer parameters in 1e-7 degrees).
pub const COMPETITION_HOME_E7: (i64, i64) = (473_977_420, 85_455_940);

/// What to start.
#[derive(Debug, Clone)]
pub struct SitlSpec {
    /// `BUILD/bin/px4` of a `px4_sitl_default` build.
    pub bin: PathBuf,
    /// Instance number: MAVLink system id `instance + 1`, API link sending to UDP `14540 + instance`.
    pub instance: u8,
    /// `PX4_SIM_SPEED_FACTOR` (SIH's lockstep speed-up).
    pub speed_factor: f64,
    /// Home (latitude, longitude) in 1e-7 degrees.
    pub home_e7: (i64, i64),
}

impl SitlSpec {
    /// The competition's home at `speed_factor`.
    pub fn new(bin: impl Into<PathBuf>, instance: u8, speed_factor: f64) -> Self {
        SitlSpec {
            bin: bin.into(),
            instance,
            speed_factor,
            home_e7: COMPETITION_HOME_E7,
        }
    }
}

/// Why an instance did not start.
#[derive(Debug, thiserror::Error)]
pub enum SitlError {
    /// The binary is not `BUILD/bin/px4` with a `BUILD/etc` beside `bin`.
    #[error("{bin}: not BUILD/bin/px4 of a PX4 SITL build ({etc} is missing)")]
    NoEtc {
        /// The binary given.
        bin: String,
        /// Where `etc` was looked for.
        etc: String,
    },
    /// The process could not be started.
    #[error("starting {bin}: {source}")]
    Spawn {
        /// The binary given.
        bin: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The startup script did not finish in time.
    #[error("PX4 instance {instance} did not finish its startup script within {secs} s")]
    Boot {
        /// The instance number.
        instance: u8,
        /// The bound waited.
        secs: u64,
    },
}

/// One running instance; killed (and its working directory removed) when dropped.
#[derive(Debug)]
pub struct Px4Sitl {
    child: Child,
    instance: u8,
    dir: PathBuf,
    console: Arc<Mutex<VecDeque<String>>>,
}

impl Px4Sitl {
    /// Starts the instance and waits (bounded) until its startup script ran, so a flight does not race the boot.
    pub fn start(spec: &SitlSpec) -> Result<Px4Sitl, SitlError> {
        let etc = etc_dir(&spec.bin);
        if !etc.is_dir() {
            return Err(SitlError::NoEtc {
                bin: spec.bin.display().to_string(),
                etc: etc.display().to_string(),
            });
        }
        let dir = work_dir(spec.instance);
        let spawn_err = |source| SitlError::Spawn {
            bin: spec.bin.display().to_string(),
            source,
        };
        std::fs::create_dir_all(&dir).map_err(spawn_err)?;
        let mut child = Command::new(&spec.bin)
            .args(["-d", "-i", &spec.instance.to_string(), "-w"])
            .arg(&dir)
            .arg(&etc)
            .env("PX4_SIM_MODEL", "sihsim_quadx")
            .env("PX4_SIMULATOR", "sihsim")
            .env("PX4_SIM_SPEED_FACTOR", spec.speed_factor.to_string())
            .env("PX4_HOME_LAT", spec.home_e7.0.to_string())
            .env("PX4_HOME_LON", spec.home_e7.1.to_string())
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .map_err(spawn_err)?;
        // The reader thread ends with the process (its stdout closes); it keeps draining so PX4 never blocks,
        // and keeps the console's last lines: PX4's own account of a flight that went wrong.
        let (tx, rx) = std::sync::mpsc::channel();
        let console = Arc::new(Mutex::new(VecDeque::with_capacity(CONSOLE_LINES)));
        if let Some(out) = child.stdout.take() {
            let console = Arc::clone(&console);
            std::thread::spawn(move || {
                for line in BufReader::new(out).lines().map_while(Result::ok) {
                    if line.contains("Startup script returned") {
                        let _ = tx.send(());
                    }
                    keep_line(&console, line);
                }
            });
        }
        let sitl = Px4Sitl {
            child,
            instance: spec.instance,
            dir,
            console,
        };
        match rx.recv_timeout(BOOT_TIMEOUT) {
            Ok(()) => Ok(sitl),
            Err(_) => Err(SitlError::Boot {
                instance: spec.instance,
                secs: BOOT_TIMEOUT.as_secs(),
            }),
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

    /// The console's last `n` lines (at most [`CONSOLE_LINES`]), oldest first, terminal colours removed.
    pub fn console_tail(&self, n: usize) -> Vec<String> {
        let lines = self.console.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        lines.iter().skip(lines.len().saturating_sub(n)).cloned().collect()
    }
}

/// Appends `line` without its ANSI colour codes, dropping the oldest line beyond [`CONSOLE_LINES`].
fn keep_line(console: &Mutex<VecDeque<String>>, line: String) {
    let plain = strip_ansi(&line);
    let mut lines = console.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    if lines.len() == CONSOLE_LINES {
        lines.pop_front();
    }
    lines.push_back(plain);
}

/// `line` without `ESC [ ... letter` sequences (PX4 colours its console's INFO/WARN tags).
fn strip_ansi(line: &str) -> String {
    let mut out = String::with_capacity(line.len());
    let mut chars = line.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            if chars.next() == Some('[') {
                for c in chars.by_ref() {
                    if c.is_ascii_alphabetic() {
                        break;
                    }
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

impl Drop for Px4Sitl {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// `BUILD/etc` for `BUILD/bin/px4`.
fn etc_dir(bin: &Path) -> PathBuf {
    bin.parent()
        .and_then(Path::parent)
        .map_or_else(|| PathBuf::from("etc"), |b| b.join("etc"))
}

/// A fresh private working directory (PX4 keeps its parameters and logs there).
fn work_dir(instance: u8) -> PathBuf {
    let nanos = SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    std::env::temp_dir().join(format!("prgenuav-px4-{}-{instance}-{nanos}", std::process::id()))
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
    fn colours_are_removed_from_console_lines() {
        assert_eq!(
            strip_ansi("INFO  [commander] \u{1b}[32mReady for takeoff!\u{1b}[0m"),
            "INFO  [commander] Ready for takeoff!"
        );
        assert_eq!(
            strip_ansi("WARN  [failsafe] Failsafe activated\t"),
            "WARN  [failsafe] Failsafe activated\t"
        );
    }

    #[test]
    fn the_console_keeps_its_last_lines() {
        let console = Mutex::new(VecDeque::new());
        for i in 0..CONSOLE_LINES + 5 {
            keep_line(&console, format!("line {i}"));
        }
        let lines = console.lock().unwrap();
        assert_eq!(lines.len(), CONSOLE_LINES);
        assert_eq!(lines.front().map(String::as_str), Some("line 5"));
        assert_eq!(lines.back(), Some(&format!("line {}", CONSOLE_LINES + 4)));
    }

    #[test]
    fn a_binary_without_etc_is_refused_with_the_path() {
        let err = Px4Sitl::start(&SitlSpec::new("/nonexistent/bin/px4", 0, 5.0)).unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("/nonexistent/etc"), "{msg}");
    }
}
