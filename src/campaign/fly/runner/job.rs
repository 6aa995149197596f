//! One job's folder: the test YAML and the files it refers to, copied in so the job is self-contained (a
//! cluster node or a container sees nothing else of the campaign).

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::model::{Spelling, TestCase, resolve_reference};

/// The test's file name in the job folder.
pub const TEST_FILE: &str = "test.yaml";
/// The job's standard output and error, kept in its folder.
pub const STDOUT_FILE: &str = "prgenuav-job.stdout";
/// See [`STDOUT_FILE`].
pub const STDERR_FILE: &str = "prgenuav-job.stderr";
/// Earlier attempts' folders of one flight kept beside it, at most (a bound on the renaming loop).
const MAX_ATTEMPT_FOLDERS: usize = 1000;

/// A job folder as written.
#[derive(Debug, Clone)]
pub struct JobFolder {
    /// The folder (absolute).
    pub dir: PathBuf,
    /// The test YAML in it (absolute).
    pub test: PathBuf,
    /// Everything prgenuav wrote there (the test, its files, the job's stdout/stderr): not job output.
    pub inputs: Vec<PathBuf>,
}

/// The blocks and keys of a test YAML that name files, in either key spelling.
const REFERENCES: [(&str, &str); 6] = [
    ("drone", "mission_file"),
    ("robot", "mission_file"),
    ("drone", "params_file"),
    ("robot", "params_file"),
    ("test", "commands_file"),
    ("mission", "commands_file"),
];

/// Writes the job folder `dir` for `test`: the files it refers to copied in and named by their file name in
/// the YAML, which is written in `spelling`. A folder left at `dir` by an earlier attempt is renamed to
/// `<dir>.attempt<K>`, kept for a look at what went wrong.
pub fn prepare(dir: &Path, test: &TestCase, spelling: Spelling) -> Result<JobFolder, String> {
    let dir = std::path::absolute(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    move_aside(&dir)?;
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create the job folder {}: {e}", dir.display()))?;
    let base = test.path.parent().unwrap_or(Path::new("."));
    let mut job_test = test.clone();
    let mut inputs = Vec::new();
    for (block, key) in REFERENCES {
        let Some(Value::Object(map)) = job_test.document.get_mut(block) else {
            continue;
        };
        let Some(Value::String(name)) = map.get(key) else {
            continue;
        };
        let source =
            resolve_reference(base, name).map_err(|e| format!("{}: {block}.{key}: {e}", test.path.display()))?;
        let file_name = unused_name(&dir, &source, &inputs);
        let target = dir.join(&file_name);
        std::fs::copy(&source, &target)
            .map_err(|e| format!("cannot copy {} into {}: {e}", source.display(), dir.display()))?;
        map.insert(key.to_string(), Value::String(file_name));
        inputs.push(target);
    }
    let test_path = dir.join(TEST_FILE);
    job_test.path = test_path.clone();
    job_test.save(&test_path, spelling).map_err(|e| e.to_string())?;
    inputs.push(test_path.clone());
    inputs.extend([dir.join(STDOUT_FILE), dir.join(STDERR_FILE)]);
    Ok(JobFolder {
        dir,
        test: test_path,
        inputs,
    })
}

/// The name `source` gets in `dir`: its own file name, numbered if an earlier reference took it.
fn unused_name(dir: &Path, source: &Path, taken: &[PathBuf]) -> String {
    let name = source
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "file".into());
    let mut candidate = name.clone();
    let mut n = 1;
    while taken.contains(&dir.join(&candidate)) || candidate == TEST_FILE {
        candidate = format!("{n}_{name}");
        n += 1;
    }
    candidate
}

/// Renames an earlier attempt's folder at `dir` to the first free `<dir>.attempt<K>`.
fn move_aside(dir: &Path) -> Result<(), String> {
    if std::fs::symlink_metadata(dir).is_err() {
        return Ok(());
    }
    for k in 1..=MAX_ATTEMPT_FOLDERS {
        let aside = PathBuf::from(format!("{}.attempt{k}", dir.display()));
        if std::fs::symlink_metadata(&aside).is_err() {
            return std::fs::rename(dir, &aside)
                .map_err(|e| format!("cannot move the earlier job folder {} aside: {e}", dir.display()));
        }
    }
    Err(format!(
        "{}: {MAX_ATTEMPT_FOLDERS} earlier attempts' folders already beside it; remove some",
        dir.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn repo() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }

    fn case() -> TestCase {
        TestCase::load(&repo().join("missions/mission2.yaml")).unwrap()
    }

    #[test]
    fn the_job_folder_holds_the_test_and_its_files() {
        let tmp = tempfile::tempdir().unwrap();
        let test = case().with_obstacles(vec![crate::model::Obstacle::new(4.0, 2.0, 20.0, 5.0, 10.0, 30.0)]);
        let job = prepare(&tmp.path().join("jobs/candidate_3"), &test, Spelling::Old).unwrap();
        let names: Vec<String> = std::fs::read_dir(&job.dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.contains(&TEST_FILE.to_string()), "{names:?}");
        // The copy loads on its own (every reference resolves inside the folder) and is the same test.
        let copy = TestCase::load(&job.test).unwrap();
        assert_eq!(copy.obstacles, test.obstacles);
        assert_eq!(copy.mission.items, test.mission.items);
        assert_eq!(copy.params, test.params);
        assert_eq!(copy.commands, test.commands);
        assert!(!copy.mission_file.contains('/'), "{}", copy.mission_file);
        assert!(job.dir.join(&copy.mission_file).is_file());
        let yaml = std::fs::read_to_string(&job.test).unwrap();
        assert!(yaml.contains("drone:"), "the campaign's spelling: {yaml}");
    }

    #[test]
    fn an_earlier_attempt_is_kept_aside() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("candidate_1");
        let first = prepare(&dir, &case(), Spelling::New).unwrap();
        std::fs::write(first.dir.join("junk.ulg"), b"x").unwrap();
        prepare(&dir, &case(), Spelling::New).unwrap();
        prepare(&dir, &case(), Spelling::New).unwrap();
        assert!(!dir.join("junk.ulg").exists());
        assert!(tmp.path().join("candidate_1.attempt1/junk.ulg").is_file());
        assert!(tmp.path().join("candidate_1.attempt2").is_dir());
    }

    #[test]
    fn a_missing_reference_is_named() {
        let tmp = tempfile::tempdir().unwrap();
        let mut test = case();
        test.path = tmp.path().join("elsewhere/t.yaml");
        for key in ["drone", "robot"] {
            if let Some(Value::Object(m)) = test.document.get_mut(key) {
                m.insert("mission_file".into(), Value::String("nowhere.plan".into()));
            }
        }
        let e = prepare(&tmp.path().join("j"), &test, Spelling::New).unwrap_err();
        assert!(e.contains("mission_file") && e.contains("nowhere.plan"), "{e}");
    }
}
