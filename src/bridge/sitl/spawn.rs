//! How an instance's process is started and stopped: PX4's arguments and environment for a headless SIH
//! quadrotor or for an external simulator, in a process group of its own that dies with the thread that
//! started it.

use std::path::Path;
use std::process::{Child, Command, Stdio};

use super::{SitlSim, SitlSpec};

/// The command starting `spec` with the build's `etc` in the working folder `dir`, the way PX4's own
/// `make px4_sitl sihsim_quadx` (or `none_iris`) target does (`-d`: no interactive shell; `-i`: instance
/// number, which sets the system id and ports; `-w`: the working folder where PX4 keeps parameters, mission
/// and logs; `-s`: the startup script, for v1.12).
pub(super) fn command(spec: &SitlSpec, etc: &Path, dir: &Path) -> Command {
    let mut cmd = Command::new(&spec.bin);
    cmd.args(["-d", "-i", &spec.instance.to_string(), "-w"]).arg(dir);
    match spec.sim {
        SitlSim::Sih(_) => {
            cmd.env("PX4_SIM_MODEL", "sihsim_quadx")
                .env("PX4_SIMULATOR", "sihsim")
                .env("PX4_SIM_SPEED_FACTOR", spec.speed_factor.to_string());
        }
        SitlSim::External(ext) => {
            // PX4_SIMULATOR set (by a SIH shell, say) would start that simulator instead of simulator_mavlink.
            cmd.env_remove("PX4_SIMULATOR").env("PX4_SIM_MODEL", ext.model);
            if let Some(script) = ext.startup {
                cmd.args(["-s", script]);
            }
        }
    }
    cmd.arg(etc)
        .envs(spec.home_env())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null());
    tie_to_parent(&mut cmd);
    cmd
}

/// Unix: a process group of its own, so the terminal's Ctrl-C reaches prgenuav alone (which lands the vehicle
/// before it stops PX4) and [`stop`] also ends the startup script's shell. Linux: PX4 also receives SIGKILL
/// when the thread that started it ends, even when prgenuav itself is killed with SIGKILL, so no orphan `px4`
/// keeps its instance's ports and lock. (Also `socat` of the serial HIL link.)
pub(crate) fn tie_to_parent(cmd: &mut Command) {
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        cmd.process_group(0);
    }
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        let parent = std::process::id() as libc::pid_t;
        // SAFETY: the hook runs between fork and exec and only makes async-signal-safe system calls
        // (prctl, getppid, _exit); it allocates nothing and takes no lock.
        unsafe {
            cmd.pre_exec(move || {
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL as libc::c_ulong, 0, 0, 0) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                // The parent may have died before prctl took effect: nobody would stop this process then.
                if libc::getppid() != parent {
                    libc::_exit(1);
                }
                Ok(())
            });
        }
    }
}

/// Kills the instance's whole process group (PX4 and a startup script still running), then reaps PX4.
pub(crate) fn stop(child: &mut Child) {
    #[cfg(unix)]
    if let Ok(pid) = libc::pid_t::try_from(child.id()) {
        // The group's leader is not reaped yet, so its id cannot have been reused.
        // SAFETY: kill(2) with a negative pid signals that process group; no memory is involved.
        unsafe {
            libc::kill(-pid, libc::SIGKILL);
        }
    }
    let _ = child.kill();
    let _ = child.wait();
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::ffi::OsStr;

    #[test]
    fn px4_gets_its_instance_folder_and_sih_environment() {
        let spec = SitlSpec::new("/b/bin/px4", 3, 5.0);
        let cmd = command(&spec, Path::new("/b/etc"), Path::new("/tmp/w"));
        assert_eq!(cmd.get_program(), OsStr::new("/b/bin/px4"));
        let args: Vec<&OsStr> = cmd.get_args().collect();
        assert_eq!(args, ["-d", "-i", "3", "-w", "/tmp/w", "/b/etc"].map(OsStr::new));
        let env: Vec<(&OsStr, Option<&OsStr>)> = cmd.get_envs().collect();
        for (key, value) in [
            ("PX4_SIM_MODEL", "sihsim_quadx"),
            ("PX4_SIMULATOR", "sihsim"),
            ("PX4_SIM_SPEED_FACTOR", "5"),
            ("PX4_HOME_LAT", "473977420"),
            ("PX4_HOME_LON", "85455940"),
        ] {
            assert!(
                env.contains(&(OsStr::new(key), Some(OsStr::new(value)))),
                "{key}={value} in {env:?}"
            );
        }
    }

    #[test]
    fn an_external_simulator_gets_the_iris_model_and_v1_12_its_startup_script() {
        let v112 = crate::bridge::px4_version::RELEASES[0].external;
        let spec = SitlSpec {
            sim: SitlSim::External(v112),
            ..SitlSpec::new("/b/bin/px4", 4, 5.0)
        };
        let cmd = command(&spec, Path::new("/b/etc"), Path::new("/tmp/w"));
        let args: Vec<&OsStr> = cmd.get_args().collect();
        assert_eq!(
            args,
            ["-d", "-i", "4", "-w", "/tmp/w", "-s", "etc/init.d-posix/rcS", "/b/etc"].map(OsStr::new)
        );
        let env: Vec<(&OsStr, Option<&OsStr>)> = cmd.get_envs().collect();
        assert!(
            env.contains(&(OsStr::new("PX4_SIM_MODEL"), Some(OsStr::new("iris")))),
            "{env:?}"
        );
        assert!(env.contains(&(OsStr::new("PX4_SIMULATOR"), None)), "removed: {env:?}");
        assert!(
            !env.iter().any(|(k, _)| k.to_string_lossy().starts_with("PX4_HOME")),
            "the simulator's GPS says where home is: {env:?}"
        );
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn stop_ends_the_whole_group() {
        // A shell that leaves a child behind, as PX4's startup script does while it runs.
        let mut cmd = Command::new("/bin/sh");
        cmd.args(["-c", "sleep 300 & echo $!; wait"]).stdout(Stdio::piped());
        tie_to_parent(&mut cmd);
        let mut child = cmd.spawn().unwrap();
        let mut line = String::new();
        std::io::BufRead::read_line(&mut std::io::BufReader::new(child.stdout.take().unwrap()), &mut line).unwrap();
        let sleeper: i32 = line.trim().parse().unwrap();
        stop(&mut child);
        // The sleeper, reparented to init, is reaped shortly after its SIGKILL.
        let gone = (0..100).any(|_| {
            std::thread::sleep(std::time::Duration::from_millis(20));
            !Path::new(&format!("/proc/{sleeper}")).exists()
                || std::fs::read_to_string(format!("/proc/{sleeper}/stat")).is_ok_and(|s| s.contains(") Z "))
        });
        assert!(gone, "the startup script's child {sleeper} outlived stop()");
    }
}
