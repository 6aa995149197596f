//! The tests of a suite folder, in suite order: its `test_N.yaml` by N (a `generate` output, best first), or,
//! in a folder without any, every `.yaml` by name, numbers in names compared as numbers (a folder of
//! Aerialist tests). Only the first `top` are read, so a broken test further down does not block them.

use std::path::{Path, PathBuf};

use crate::model::{Arena, ModelError, TestCase};
use crate::rules::{Violation, check, judgeable};

/// How the tests are held to the competition's rules.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rules {
    /// An invalid test is refused, naming the file and the rule (`evaluate`: it flies them).
    Refuse,
    /// Told of, and scored as flown (`score`: the flights exist); a test without obstacles is still refused.
    Warn,
}

/// The suite's test files, in suite order ([the module's rule](self)).
pub fn test_files(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut yaml: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "yaml") && p.is_file())
        .collect();
    let numbered: Vec<(u64, PathBuf)> = yaml.iter().filter_map(|p| Some((test_number(p)?, p.clone()))).collect();
    if !numbered.is_empty() {
        let mut numbered = numbered;
        numbered.sort();
        return Ok(numbered.into_iter().map(|(_, p)| p).collect());
    }
    yaml.sort_by_key(|p| natural_key(p));
    Ok(yaml)
}

/// N of `test_N.yaml`.
fn test_number(p: &Path) -> Option<u64> {
    p.file_name()?
        .to_str()?
        .strip_prefix("test_")?
        .strip_suffix(".yaml")?
        .parse()
        .ok()
}

/// A file name split into text and numbers, so `case_2` sorts before `case_10`.
fn natural_key(p: &Path) -> Vec<(String, u64)> {
    let name = p
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut key = Vec::new();
    let (mut text, mut digits) = (String::new(), String::new());
    for c in name.chars().chain(std::iter::once('\0')) {
        if c.is_ascii_digit() {
            digits.push(c);
            continue;
        }
        if !digits.is_empty() {
            key.push((std::mem::take(&mut text), digits.parse().unwrap_or(u64::MAX)));
            digits.clear();
        }
        text.push(c);
    }
    key.push((text, 0));
    key
}

/// Loads the first `top` tests of `dir` (all without `top`), refusing tests of different missions (the
/// competition evaluates one mission at a time) and holding each to the competition's rules as `rules` says.
pub fn load_tests(dir: &Path, top: Option<usize>, rules: Rules) -> Result<Vec<(PathBuf, TestCase)>, ModelError> {
    let mut paths = test_files(dir).map_err(|source| ModelError::Io {
        path: dir.to_path_buf(),
        action: "cannot list",
        source,
    })?;
    if paths.is_empty() {
        return Err(ModelError::field(
            dir,
            "test_N.yaml",
            "the folder holds no test (no test_N.yaml, and no other .yaml file)",
        ));
    }
    paths.truncate(top.unwrap_or(usize::MAX).max(1));
    let mut tests: Vec<(PathBuf, TestCase)> = Vec::with_capacity(paths.len());
    for p in paths {
        let t = TestCase::load(&p)?;
        if let Some((first, f)) = tests.first()
            && (f.mission.items != t.mission.items || f.mission.home != t.mission.home)
        {
            return Err(ModelError::field(
                &p,
                "mission_file",
                format!(
                    "flies another mission than {} ({} vs {}); evaluate one mission per folder",
                    first.display(),
                    t.mission_file,
                    f.mission_file
                ),
            ));
        }
        hold_to_rules(&p, &t, rules)?;
        tests.push((p, t));
    }
    Ok(tests)
}

fn hold_to_rules(path: &Path, test: &TestCase, rules: Rules) -> Result<(), ModelError> {
    if let Some(v) = judgeable(test) {
        return Err(refusal(path, &[v]));
    }
    let violations = check(test, &Arena::default());
    match rules {
        _ if violations.is_empty() => Ok(()),
        Rules::Refuse => Err(refusal(path, &violations)),
        Rules::Warn => {
            for v in &violations {
                eprintln!(
                    "warning: {}: breaks the competition's rules, which would not fly it; scored as flown: {} = {}: {}",
                    path.display(),
                    v.path,
                    v.value,
                    v.rule
                );
            }
            Ok(())
        }
    }
}

fn refusal(path: &Path, violations: &[Violation]) -> ModelError {
    let first = &violations[0];
    let more = match violations.len() {
        1 => String::new(),
        n => format!(" (and {} more: `prgenuav check {}` lists them)", n - 1, path.display()),
    };
    ModelError::field(
        path,
        first.path.clone(),
        format!(
            "{} = {}: {}{more}; the competition flies valid tests only: fix or remove the test",
            first.path, first.value, first.rule
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbered_tests_come_first_else_every_yaml_in_natural_order() {
        let dir = tempfile::tempdir().unwrap();
        for n in ["case_10.yaml", "case_2.yaml", "b.yaml", "notes.txt"] {
            std::fs::write(dir.path().join(n), "").unwrap();
        }
        let names = |d: &Path| -> Vec<String> {
            (test_files(d).unwrap().iter())
                .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
                .collect()
        };
        assert_eq!(names(dir.path()), ["b.yaml", "case_2.yaml", "case_10.yaml"]);
        for n in ["test_10.yaml", "test_2.yaml"] {
            std::fs::write(dir.path().join(n), "").unwrap();
        }
        assert_eq!(names(dir.path()), ["test_2.yaml", "test_10.yaml"]);
    }
}
