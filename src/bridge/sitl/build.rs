//! The user's PX4 SITL build folder (`px4_sitl_default`), checked before anything is started: a folder that is
//! not such a build is refused naming what is missing, so a campaign does not screen for minutes and then fail
//! on its first flight. The build's PX4 version is read from the version header its build generated, and a
//! release prgenuav has not checked is refused by name.

use std::path::{Path, PathBuf};

use crate::bridge::bench::Bench;
use crate::bridge::options::{FlyMode, VehicleSim};
use crate::bridge::px4_version::{Px4Version, Release, mode_refusal};

/// The startup script PX4's POSIX main runs, relative to the build folder.
const RCS: &str = "etc/init.d-posix/rcS";

/// The header PX4's build generates from `git describe`, relative to the build folder.
pub const VERSION_HEADER: &str = "src/lib/version/build_git_version.h";

/// A checked `px4_sitl_default` build folder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Px4Build {
    /// The folder as given.
    pub root: PathBuf,
    /// Its PX4 version (from [`VERSION_HEADER`]).
    pub version: Px4Version,
    /// What that release can do.
    pub release: &'static Release,
}

/// Why a folder is not a PX4 SITL build.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "{root}: not a PX4 SITL build folder prgenuav can fly (build/px4_sitl_default of PX4-Autopilot v1.12 to \
     v1.17, built with `make px4_sitl_default`): {missing}"
)]
pub struct NotABuild {
    /// The folder given.
    pub root: String,
    /// What is missing or wrong, naming the path.
    pub missing: String,
}

impl Px4Build {
    /// Checks `root`: a folder with an executable `bin/px4`, `etc/init.d-posix/rcS` and the version header of
    /// a release in the capability table.
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
        let (version, release) = read_version(root).map_err(refuse)?;
        Ok(Px4Build {
            root: root.to_path_buf(),
            version,
            release,
        })
    }

    /// `bin/px4`.
    pub fn bin(&self) -> PathBuf {
        self.root.join("bin/px4")
    }

    /// Whether `mode` flies on this build's release; if not, the refusal naming the version and the modes
    /// that do.
    pub fn check_mode(&self, mode: FlyMode) -> Result<(), ModeUnsupported> {
        if self.release.supports(mode) {
            return Ok(());
        }
        Err(ModeUnsupported(format!(
            "{}: {}",
            self.root.display(),
            mode_refusal(&self.version, self.release, mode)
        )))
    }
}

impl Px4Build {
    /// Whether this build can fly with `sim`: v1.12 has no SIH in SITL, and an external simulator needs
    /// the build's `simulator_mavlink` module (v1.12: `simulator`), whose command sits in `bin/`.
    pub fn check_sim(&self, sim: VehicleSim) -> Result<(), ModeUnsupported> {
        let root = self.root.display();
        if let Some(why) = self.release.sim_refusal(&self.version, sim) {
            return Err(ModeUnsupported(format!("{root}: {why}")));
        }
        let module = self.root.join("bin").join(self.release.external.module);
        if sim == VehicleSim::Iris && !module.exists() {
            let name = self.release.external.module.trim_start_matches("px4-");
            return Err(ModeUnsupported(format!(
                "{root}: --sim iris: {} is missing, so this build has no external-simulator support (PX4's \
                 `{name}` module); build px4_sitl_default with its simulation modules (CONFIG_COMMON_SIMULATION=y \
                 from v1.14, `{name}` in boards/px4/sitl/default.cmake in v1.12), or fly --sim sih",
                module.display()
            )));
        }
        Ok(())
    }
}

impl Px4Build {
    /// Whether this build's release may fly `bench` ([`Bench::release_refusal`]).
    pub fn check_bench(&self, bench: Bench) -> Result<(), ModeUnsupported> {
        match bench.release_refusal(&self.version) {
            Some(why) => Err(ModeUnsupported(format!("{}: {why}", self.root.display()))),
            None => Ok(()),
        }
    }
}

/// A mode the build's release cannot fly, in words.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct ModeUnsupported(pub String);

/// The build's version and its row of the capability table, or what was read instead.
fn read_version(root: &Path) -> Result<(Px4Version, &'static Release), String> {
    let header = root.join(VERSION_HEADER);
    let text = std::fs::read_to_string(&header).map_err(|e| {
        format!(
            "{} (the version PX4's build generates) is not readable: {e}",
            header.display()
        )
    })?;
    let tag = tag_in_header(&text).ok_or_else(|| format!("{} has no PX4_GIT_TAG_STR line", header.display()))?;
    let version = Px4Version::parse(tag).ok_or_else(|| {
        format!(
            "{} says PX4_GIT_TAG_STR \"{tag}\", not a version vMAJOR.MINOR.PATCH (build from a release tag)",
            header.display()
        )
    })?;
    let release = version
        .release()
        .map_err(|e| format!("{e} (read from {})", header.display()))?;
    Ok((version, release))
}

/// The quoted value of `#define PX4_GIT_TAG_STR "..."`.
fn tag_in_header(text: &str) -> Option<&str> {
    text.lines().find_map(|line| {
        let rest = line.trim().strip_prefix("#define")?.trim_start();
        let value = rest.strip_prefix("PX4_GIT_TAG_STR")?.trim();
        value.strip_prefix('"')?.split('"').next()
    })
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

    /// A version header as PX4's build writes it, with `tag`.
    fn header(tag: &str) -> String {
        format!(
            "/* Auto Magically Generated file */\n#pragma once\n\n#define PX4_GIT_VERSION_STR \"54f0455f\"\n\
             #define PX4_GIT_TAG_STR \"{tag}\"\n#define PX4_GIT_TAG_OR_BRANCH_NAME \"main\"\n"
        )
    }

    /// A build folder with the parts named in `parts` (`bin`, `exec`, `etc`, `rcs`, `ver`: a v1.14 header).
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
        if parts.contains(&"ver") {
            write_header(root, &header("v1.14.0-beta2-325-g1555f2bd22"));
        }
        dir
    }

    fn write_header(root: &Path, text: &str) {
        std::fs::create_dir_all(root.join("src/lib/version")).unwrap();
        std::fs::write(root.join(VERSION_HEADER), text).unwrap();
    }

    const ALL: [&str; 5] = ["bin", "exec", "etc", "rcs", "ver"];

    fn refusal(parts: &[&str]) -> String {
        let dir = folder(parts);
        Px4Build::open(dir.path()).unwrap_err().to_string()
    }

    #[test]
    fn a_complete_build_is_accepted() {
        let dir = folder(&ALL);
        let build = Px4Build::open(dir.path()).unwrap();
        assert_eq!(build.bin(), dir.path().join("bin/px4"));
        assert_eq!(build.version.to_string(), "v1.14.0-beta2-325-g1555f2bd22");
        assert!(build.release.avoidance_interface);
    }

    #[test]
    fn each_missing_part_is_named() {
        assert!(refusal(&["etc", "rcs"]).contains("bin/px4 is missing"));
        #[cfg(unix)]
        assert!(refusal(&["bin", "etc", "rcs"]).contains("bin/px4 is not executable"));
        assert!(refusal(&["bin", "exec"]).contains("/etc is missing"));
        assert!(refusal(&["bin", "exec", "etc"]).contains("init.d-posix/rcS (PX4's startup script) is missing"));
        let no_header = refusal(&["bin", "exec", "etc", "rcs"]);
        assert!(
            no_header.contains("build_git_version.h (the version PX4's build generates) is not readable"),
            "{no_header}"
        );
        let missing = Px4Build::open(Path::new("/nonexistent/px4_sitl_default")).unwrap_err();
        assert_eq!(missing.missing, "no such folder");
        assert!(
            missing
                .to_string()
                .contains("/nonexistent/px4_sitl_default: not a PX4 SITL build folder")
        );
    }

    #[test]
    fn the_version_header_decides_the_release_and_an_unknown_one_is_refused_naming_what_was_read() {
        let dir = folder(&ALL);
        let open = |text: &str| {
            write_header(dir.path(), text);
            Px4Build::open(dir.path())
        };
        let v116 = open(&header("v1.16.2")).unwrap();
        assert_eq!((v116.release.minor, v116.release.avoidance_interface), (16, false));
        let refused = v116.check_mode(FlyMode::Avoidance).unwrap_err().to_string();
        assert!(
            refused.contains("--mode avoidance: PX4 v1.16.2 has no obstacle-avoidance interface"),
            "{refused}"
        );
        assert!(
            refused.ends_with("modes that work on PX4 1.16: offboard, mission, collision-prevention"),
            "{refused}"
        );
        assert_eq!(v116.check_mode(FlyMode::Offboard), Ok(()));
        let newer = open(&header("v1.18.0-beta1")).unwrap_err().to_string();
        assert!(
            newer.contains("PX4 v1.18.0-beta1 (read as 1.18) has not been checked"),
            "{newer}"
        );
        assert!(newer.contains("build_git_version.h"), "{newer}");
        let branch = open(&header("my-branch")).unwrap_err().to_string();
        assert!(
            branch.contains("says PX4_GIT_TAG_STR \"my-branch\", not a version"),
            "{branch}"
        );
        let garbled = open("#define PX4_GIT_VERSION_STR \"abc\"\n").unwrap_err().to_string();
        assert!(garbled.contains("has no PX4_GIT_TAG_STR line"), "{garbled}");
        assert_eq!(
            tag_in_header("  #define   PX4_GIT_TAG_STR   \"v1.15.4\"  "),
            Some("v1.15.4")
        );
        assert_eq!(tag_in_header("#define PX4_GIT_TAG_STR_X \"v1\""), None);
    }

    #[test]
    fn a_build_without_the_external_simulator_module_is_refused_for_the_iris_and_v1_12_for_sih() {
        let dir = folder(&ALL);
        let b = Px4Build::open(dir.path()).unwrap();
        let e = b.check_sim(VehicleSim::Iris).unwrap_err().to_string();
        assert!(
            e.contains("bin/px4-simulator_mavlink is missing") && e.contains("no external-simulator support"),
            "{e}"
        );
        assert_eq!(b.check_sim(VehicleSim::Sih), Ok(()));
        std::fs::write(dir.path().join("bin/px4-simulator_mavlink"), "").unwrap();
        assert_eq!(b.check_sim(VehicleSim::Iris), Ok(()));
        write_header(dir.path(), &header("v1.12.3"));
        let v112 = Px4Build::open(dir.path()).unwrap();
        let e = v112.check_sim(VehicleSim::Sih).unwrap_err().to_string();
        assert!(e.contains("has no SIH in SITL") && e.contains("--sim iris"), "{e}");
        let e = v112.check_sim(VehicleSim::Iris).unwrap_err().to_string();
        assert!(e.contains("bin/px4-simulator is missing"), "{e}");
        std::fs::write(dir.path().join("bin/px4-simulator"), "").unwrap();
        assert_eq!(v112.check_sim(VehicleSim::Iris), Ok(()));
    }

    #[test]
    fn a_file_is_not_a_build_folder() {
        let dir = folder(&[]);
        let file = dir.path().join("px4");
        std::fs::write(&file, "").unwrap();
        assert_eq!(Px4Build::open(&file).unwrap_err().missing, "no such folder");
    }
}
