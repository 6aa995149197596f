//! The files a case study or test names (`mission_file`, `params_file`, `commands_file`): where a relative
//! name is looked for, and how a written test names them so it loads from any folder.
//!
//! Aerialist reads a relative name against the working folder, so that comes first; a user who runs from
//! elsewhere finds the files beside the YAML or in one of its parent folders (a case in `missions/` naming
//! `missions/mission2.plan` resolves from the repository root this way).

use std::path::{Path, PathBuf};

use serde_json::Value;

use serde_json::Map;

use super::error::{ModelError, Result};

/// The blocks and keys of a test YAML that name files, in either key spelling.
const REFERENCES: [(&str, &str); 6] = [
    ("drone", "mission_file"),
    ("robot", "mission_file"),
    ("drone", "params_file"),
    ("robot", "params_file"),
    ("test", "commands_file"),
    ("mission", "commands_file"),
];

/// The places a relative `name` is looked for, in order: the working folder, then `base` (the YAML's folder)
/// and each of its parents. An absolute `name` is only itself. No place is listed twice.
pub(crate) fn candidates(base: &Path, name: &str) -> Vec<PathBuf> {
    let given = Path::new(name);
    if given.is_absolute() {
        return vec![given.to_path_buf()];
    }
    let base = if base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base
    };
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut out = vec![absolute(given)];
    for folder in absolute(base).ancestors() {
        let p = folder.join(given);
        if !out.contains(&p) {
            out.push(p);
        }
    }
    out
}

/// Resolves a file named in a YAML read from the folder `base` (see [`candidates`] for the order); the error
/// lists every place tried.
pub(crate) fn resolve(base: &Path, name: &str) -> std::result::Result<PathBuf, String> {
    let tried = candidates(base, name);
    // The file found, without `..` or symbolic links: the name a written test keeps.
    let found = tried
        .iter()
        .find(|p| p.is_file())
        .map(|p| std::fs::canonicalize(p).unwrap_or_else(|_| p.clone()));
    found.ok_or_else(|| {
        // A folder (or a device) by that name is what the user most likely meant: say so rather than "not found".
        if let Some(p) = tried.iter().find(|p| p.exists()) {
            let what = if p.is_dir() { "a folder" } else { "not a regular file" };
            return format!("{name:?} names {}, which is {what}: it must name a file", p.display());
        }
        let list: Vec<String> = tried.iter().map(|p| p.display().to_string()).collect();
        format!(
            "file {name:?} not found (tried, in order: {}; a relative name is looked for in the working folder, \
             then beside the YAML and in its parent folders)",
            list.join(", ")
        )
    })
}

/// Rewrites the file references of `document`, a YAML read from `yaml`, as absolute paths; returns the new
/// `mission_file`, if it names one.
pub(crate) fn make_absolute(document: &mut Map<String, Value>, yaml: &Path) -> Result<Option<String>> {
    let base = yaml.parent().unwrap_or(Path::new("."));
    let mut mission_file = None;
    for (block, key) in REFERENCES {
        let Some(Value::Object(map)) = document.get_mut(block) else {
            continue;
        };
        let Some(Value::String(name)) = map.get(key) else {
            continue;
        };
        let found = resolve(base, name).map_err(|m| ModelError::field(yaml, format!("{block}.{key}"), m))?;
        let found = found.display().to_string();
        if key == "mission_file" {
            mission_file = Some(found.clone());
        }
        map.insert(key.to_string(), Value::String(found));
    }
    Ok(mission_file)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::TestCase;

    fn repo() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }

    #[test]
    fn the_working_folder_comes_first_then_the_yaml_folder_and_its_parents() {
        let base = repo().join("missions");
        let c = candidates(&base, "missions/mission2.plan");
        assert_eq!(c[0], std::path::absolute("missions/mission2.plan").unwrap());
        assert_eq!(c[1], base.join("missions/mission2.plan"));
        // The repository root (a parent of the YAML's folder) is the working folder here: not listed twice.
        assert_eq!(c[2], repo().parent().unwrap().join("missions/mission2.plan"));
        assert_eq!(c.last().unwrap(), Path::new("/missions/mission2.plan"));
        assert_eq!(candidates(&base, "/x/y.plan"), vec![PathBuf::from("/x/y.plan")]);
    }

    #[test]
    fn a_case_resolves_its_files_from_a_parent_of_its_folder() {
        let found = resolve(&repo().join("missions"), "missions/mission2.plan").unwrap();
        assert_eq!(found, repo().join("missions/mission2.plan"));
    }

    #[test]
    fn a_name_that_is_a_folder_is_told_as_a_folder() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("mission.plan")).unwrap();
        let e = resolve(dir.path(), &dir.path().join("mission.plan").display().to_string()).unwrap_err();
        assert!(e.contains("which is a folder: it must name a file"), "{e}");
        assert!(!e.contains("not found"), "{e}");
    }

    #[test]
    fn not_found_lists_every_place_tried() {
        let dir = tempfile::tempdir().unwrap();
        let e = resolve(&dir.path().join("a/b"), "nowhere.plan").unwrap_err();
        assert!(
            e.contains(&dir.path().join("a/b/nowhere.plan").display().to_string()),
            "{e}"
        );
        assert!(
            e.contains(&dir.path().join("a/nowhere.plan").display().to_string()),
            "{e}"
        );
        assert!(e.contains("/nowhere.plan;") || e.contains("/nowhere.plan)"), "{e}");
        assert!(e.contains("working folder"), "{e}");
    }

    #[test]
    fn a_written_test_names_its_files_absolutely_and_loads_from_elsewhere() {
        let case = TestCase::load(&repo().join("missions/mission2.yaml")).unwrap();
        let portable = case.with_absolute_references().unwrap();
        assert!(
            Path::new(&portable.mission_file).is_absolute(),
            "{}",
            portable.mission_file
        );
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("deep/test_0.yaml");
        portable.save(&path, case.spelling).unwrap();
        let back = TestCase::load(&path).unwrap();
        assert_eq!(back.mission, case.mission);
        assert_eq!(back.params, case.params);
        assert_eq!(back.commands, case.commands);
        assert_eq!(
            portable.with_absolute_references().unwrap().document,
            portable.document,
            "idempotent"
        );
    }
}
