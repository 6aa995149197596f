//! The serial HIL link to PX4 SITL (`--sim-link serial`): `socat` listens on PX4's TCP port `4560 + i` and
//! joins the connection to a pseudo-terminal, which the simulator opens as a board's serial port and runs on
//! the wall clock, as it would a flight controller's USB port. `socat` is started and stopped here (its own
//! process group, killed with this process), and checked present before anything starts.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::bridge::sitl::{kill_group, tie_to_parent};

/// How long socat may take to create its pty.
const PTY_WAIT: Duration = Duration::from_secs(5);

/// A running `socat` between TCP `127.0.0.1:4560+i` and a pty; killed when dropped.
#[derive(Debug)]
pub struct PtyBridge {
    child: Child,
    link: PathBuf,
}

/// Why the serial link could not be set up, with what to do about it.
#[derive(Debug, thiserror::Error)]
pub enum PtyError {
    /// socat is not installed.
    #[error(
        "--sim-link serial needs socat to join PX4's TCP port to a serial pty, and `socat` is not on PATH: \
         install it (Debian/Ubuntu: apt-get install socat), or fly --sim-link tcp"
    )]
    NoSocat,
    /// PX4's port is taken.
    #[error(
        "TCP port {port} is in use: another simulator (Gazebo, jMAVSim, prgenuav-sim) is serving it; stop it, \
         or use another instance (PX4 instance N connects to 4560+N)"
    )]
    PortInUse {
        /// The port.
        port: u16,
    },
    /// socat did not start or did not make its pty.
    #[error("socat for the serial HIL link: {0}")]
    Failed(String),
}

impl PtyBridge {
    /// Starts socat for PX4 instance `instance`, its pty linked at `dir/prgenuav-hil-pty-<i>`; returns once
    /// the pty exists.
    pub fn start(instance: u8, dir: &Path) -> Result<PtyBridge, PtyError> {
        let socat = which("socat").ok_or(PtyError::NoSocat)?;
        let port = 4560 + u16::from(instance);
        // socat would fail later, silently for us: say it now, naming the port.
        drop(std::net::TcpListener::bind(("127.0.0.1", port)).map_err(|_| PtyError::PortInUse { port })?);
        let link = dir.join(format!("prgenuav-hil-pty-{instance}"));
        let _ = std::fs::remove_file(&link);
        let mut cmd = Command::new(socat);
        cmd.arg(format!("PTY,link={},raw,echo=0", link.display()))
            .arg(format!("TCP-LISTEN:{port},bind=127.0.0.1,reuseaddr"))
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        tie_to_parent(&mut cmd);
        let child = cmd
            .spawn()
            .map_err(|e| PtyError::Failed(format!("cannot start it: {e}")))?;
        let mut bridge = PtyBridge { child, link };
        bridge.wait_for_pty()?;
        Ok(bridge)
    }

    fn wait_for_pty(&mut self) -> Result<(), PtyError> {
        let deadline = Instant::now() + PTY_WAIT;
        while !self.link.exists() {
            if let Ok(Some(status)) = self.child.try_wait() {
                let mut said = String::new();
                if let Some(mut err) = self.child.stderr.take() {
                    let _ = std::io::Read::read_to_string(&mut err, &mut said);
                }
                return Err(PtyError::Failed(format!("exited ({status}): {}", said.trim())));
            }
            if Instant::now() >= deadline {
                return Err(PtyError::Failed(format!(
                    "no pty at {} within {PTY_WAIT:?}",
                    self.link.display()
                )));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        // Its diagnostics are not read once it runs: a full pipe must not block it.
        self.child.stderr.take();
        Ok(())
    }

    /// The pty's path, for the simulator's serial port.
    pub fn device(&self) -> String {
        self.link.display().to_string()
    }

    /// Whether socat is still running.
    pub fn running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }
}

impl Drop for PtyBridge {
    fn drop(&mut self) {
        kill_group(&mut self.child);
        let _ = std::fs::remove_file(&self.link);
    }
}

/// `name` found on PATH.
fn which(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| is_executable(p))
}

#[cfg(unix)]
fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

#[cfg(not(unix))]
fn is_executable(p: &Path) -> bool {
    p.is_file()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn socat_joins_the_port_to_a_pty_and_goes_with_the_bridge() {
        if which("socat").is_none() {
            // The refusal is all there is to check without it.
            let e = PtyBridge::start(8, &std::env::temp_dir()).unwrap_err().to_string();
            assert!(e.contains("apt-get install socat"), "{e}");
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let Ok(mut bridge) = PtyBridge::start(8, dir.path()) else {
            return; // port 4568 taken on this machine: nothing to learn here
        };
        assert!(bridge.running() && Path::new(&bridge.device()).exists());
        // socat listens a moment after it made the pty.
        std::thread::sleep(Duration::from_millis(300));
        let squatted = PtyBridge::start(8, dir.path()).unwrap_err().to_string();
        assert!(squatted.contains("TCP port 4568 is in use"), "{squatted}");
        let device = bridge.device();
        drop(bridge);
        assert!(!Path::new(&device).exists(), "the pty link goes with socat");
    }
}
