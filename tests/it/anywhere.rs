//! Commands work from any folder: a case's relative file names resolve from the working folder, then beside
//! the YAML and its parents; the tests prgenuav writes load from anywhere; a file not found lists every place
//! tried.

use std::path::{Path, PathBuf};

use super::repo;

/// Runs `prgenuav` in `dir`; returns (exit code, stdout, stderr).
pub fn prgenuav_in(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_prgenuav"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run prgenuav");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A copy of the public missions in `root/missions` (a clone of the repository's layout elsewhere).
pub fn copy_missions(root: &Path) -> PathBuf {
    let missions = root.join("missions");
    std::fs::create_dir_all(&missions).unwrap();
    for e in std::fs::read_dir(repo().join("missions")).unwrap().flatten() {
        std::fs::copy(e.path(), missions.join(e.file_name())).unwrap();
    }
    missions
}

#[test]
fn a_case_loads_by_absolute_and_relative_path_from_outside_the_repository() {
    let tmp = tempfile::tempdir().unwrap();
    let missions = copy_missions(&tmp.path().join("clone"));
    let elsewhere = tmp.path().join("work/deeper");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let absolute = missions.join("mission2.yaml");
    for (case, out) in [
        (absolute.to_str().unwrap(), "a"),
        ("../../clone/missions/mission2.yaml", "b"),
    ] {
        let (code, stdout, stderr) = prgenuav_in(&elsewhere, &["sample", case, "2", "-o", out]);
        assert_eq!(code, 0, "{case}: {stdout}{stderr}");
        assert!(stdout.contains("wrote 2 tests"), "{stdout}");
    }
    // The written tests name their files absolutely: they check from yet another folder, and alike.
    let a = std::fs::read_to_string(elsewhere.join("a/test_1.yaml")).unwrap();
    let b = std::fs::read_to_string(elsewhere.join("b/test_1.yaml")).unwrap();
    assert_eq!(a, b);
    assert!(
        a.contains(&format!("mission_file: {}", missions.join("mission2.plan").display())),
        "{a}"
    );
    let (code, out, err) = prgenuav_in(tmp.path(), &["check", "work/deeper/a/test_1.yaml"]);
    assert_eq!(code, 0, "{out}{err}");
}

#[test]
fn a_missing_file_lists_every_place_tried_in_order() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cases");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("case.yaml"), "drone:\n  mission_file: missions/none.plan\n").unwrap();
    let (code, _, err) = prgenuav_in(tmp.path(), &["sample", "cases/case.yaml", "1", "-o", "o"]);
    assert_eq!(code, 2, "{err}");
    let tried = [
        tmp.path().join("missions/none.plan"),
        dir.join("missions/none.plan"),
        PathBuf::from("/missions/none.plan"),
    ];
    let at: Vec<usize> = tried
        .iter()
        .map(|p| {
            err.find(&p.display().to_string())
                .unwrap_or_else(|| panic!("{} not in {err}", p.display()))
        })
        .collect();
    assert!(at[0] < at[1], "the working folder first, then beside the YAML: {err}");
    assert!(
        err.contains("drone.mission_file") && !tmp.path().join("o").exists(),
        "{err}"
    );
}

#[test]
fn sample_refuses_a_folder_with_files_unless_forced() {
    let tmp = tempfile::tempdir().unwrap();
    let case = repo().join("missions/mission2.yaml");
    let case = case.to_str().unwrap();
    let (code, _, err) = prgenuav_in(tmp.path(), &["sample", case, "3", "-o", "s"]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = prgenuav_in(tmp.path(), &["sample", case, "1", "-o", "s"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("already holds 3 files") && err.contains("--force"),
        "{err}"
    );
    let (code, _, err) = prgenuav_in(tmp.path(), &["sample", case, "--count", "1", "-o", "s", "--force"]);
    assert_eq!(code, 0, "{err}");
    let left = std::fs::read_dir(tmp.path().join("s")).unwrap().count();
    assert_eq!(left, 1, "the earlier run's test_1 and test_2 are gone");
}

/// Every path the JSON values `named` hold is absolute and names an existing file.
pub fn assert_absolute_files(named: &[&serde_json::Value]) {
    for p in named {
        let p = Path::new(p.as_str().unwrap());
        assert!(p.is_absolute() && p.is_file(), "{}", p.display());
    }
}
