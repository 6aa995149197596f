//! The user's PX4 SITL build folder (`px4_sitl_default`), checked before anything is started: a folder that is
//! not such a build is refused naming what is missing, so a campaign does not screen for minutes and then fail
//! on its first flight.

use std::path::{Path, PathBuf};

/// The startup script PX4's POSIX main runs, relative to the build folder.
const RCS: &str = "etc/init.d-posix/rcS";

/// A checked `px4_sitl_default` build folder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Px4Build {
    /// The folder as given.
    pub root: PathBuf,
}

/// Why a folder is not a PX4 SITL build.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{root}: not a PX4 SITL build folder (build/px4_sitl_default of PX4-Autopilot v1.14, built with \
     `make px4_sitl_default`): {missing}"
)]
pub struct NotABuild {
    /// The folder given.
    pub root: String,
    /// What is missing or wrong, naming the path.
    pub missing: String,
}

impl Px4Build {
    /// Checks `root`: a folder with an executable `bin/px4` and `etc/init.d-posix/rcS`.
    pub fn open(root: &Path) -> Result<Px4Build, NotABuild> {
        let refuse = |missing: String| NotABuild {
            root: root.display().to_string(),
            missing,
        };
        if !root.is_dir() {
            return Err(refuse("no such folder".into()));
        }
        let bin = root.join("bin/px4");
        if !bin.is_file() {
            return Err(refuse(format!("{} is missing", bin.display())));
        }
        if !is_executable(&bin) {
            return Err(refuse(format!("{} is not executable", bin.display())));
        }
        let etc = root.join("etc");
        if !etc.is_dir() {
            return Err(refuse(format!("{} is missing", etc.display())));
        }
        let rcs = root.join(RCS);
        if !rcs.is_file() {
            return Err(refuse(format!("{} (PX4's startup script) is missing", rcs.display())));
        }
        Ok(Px4Build {
            root: root.to_path_buf(),
        })
    }

    /// `bin/px4`.
    pub fn bin(&self) -> PathBuf {
        self.root.join("bin/px4")
    }
}

#[cfg(unix)]
fn is_executable(path: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    std::fs::metadata(path).is_ok_and(|m| m.permissions().mode() & 0o111 != 0)
}

#[cfg(not(unix))]
fn is_executable(_path: &Path) -> bool {
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A build folder with the parts named in `parts` (`bin`, `exec`, `etc`, `rcs`).
    fn folder(parts: &[&str]) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        if parts.contains(&"bin") {
            std::fs::create_dir_all(root.join("bin")).unwrap();
            std::fs::write(root.join("bin/px4"), "#!/bin/sh\n").unwrap();
            #[cfg(unix)]
            if parts.contains(&"exec") {
                use std::os::unix::fs::PermissionsExt;
                std::fs::set_permissions(root.join("bin/px4"), std::fs::Permissions::from_mode(0o755)).unwrap();
            }
        }
        if parts.contains(&"etc") {
            std::fs::create_dir_all(root.join("etc/init.d-posix")).unwrap();
        }
        if parts.contains(&"rcs") {
            std::fs::write(root.join(RCS), "").unwrap();
        }
        dir
    }

    fn refusal(parts: &[&str]) -> String {
        let dir = folder(parts);
        Px4Build::open(dir.path()).unwrap_err().to_string()
    }

    #[test]
    fn a_complete_build_is_accepted() {
        let dir = folder(&["bin", "exec", "etc", "rcs"]);
        let build = Px4Build::open(dir.path()).unwrap();
        assert_eq!(build.bin(), dir.path().join("bin/px4"));
    }

    #[test]
    fn each_missing_part_is_named() {
        assert!(refusal(&["etc", "rcs"]).contains("bin/px4 is missing"));
        #[cfg(unix)]
        assert!(refusal(&["bin", "etc", "rcs"]).contains("bin/px4 is not executable"));
        assert!(refusal(&["bin", "exec"]).contains("/etc is missing"));
        assert!(refusal(&["bin", "exec", "etc"]).contains("init.d-posix/rcS (PX4's startup script) is missing"));
        let missing = Px4Build::open(Path::new("/nonexistent/px4_sitl_default")).unwrap_err();
        assert_eq!(missing.missing, "no such folder");
        assert!(
            missing
                .to_string()
                .contains("/nonexistent/px4_sitl_default: not a PX4 SITL build folder")
        );
    }

    #[test]
    fn a_file_is_not_a_build_folder() {
        let dir = folder(&[]);
        let file = dir.path().join("px4");
        std::fs::write(&file, "").unwrap();
        assert_eq!(Px4Build::open(&file).unwrap_err().missing, "no such folder");
    }
}
