//! The README against the binary: every exit code it documents and every file it says a campaign folder
//! holds. Commands run from a folder outside the repository, with the case by absolute path.

use std::path::Path;

use super::anywhere::prgenuav_in;
use prgenuav::model::{Obstacle, Spelling};

use super::{case, repo, valid_pair};

/// A test of mission 2 with `obstacles` in `dir`, naming its files absolutely (loadable from anywhere).
fn test_in(dir: &Path, name: &str, obstacles: Vec<Obstacle>) -> String {
    let path = dir.join(name);
    let test = case(2).with_absolute_references().unwrap().with_obstacles(obstacles);
    test.save(&path, Spelling::New).unwrap();
    path.to_str().unwrap().to_string()
}

/// The README with its line breaks folded, so a sentence reads the same wherever it wraps.
fn readme() -> String {
    let text = std::fs::read_to_string(repo().join("README.md")).expect("README.md");
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

#[test]
fn every_documented_exit_code_holds() {
    let doc = readme();
    let tmp = tempfile::tempdir().unwrap();
    let here = tmp.path();
    let valid = &test_in(here, "valid.yaml", valid_pair());
    let invalid = &test_in(
        here,
        "invalid.yaml",
        vec![Obstacle::new(21.0, 3.0, 20.0, -20.0, 25.0, 10.0)],
    );

    assert!(
        doc.contains("(exit 0 valid, 1 violations, 2 unreadable)"),
        "check's codes"
    );
    assert_eq!(prgenuav_in(here, &["check", valid]).0, 0);
    assert_eq!(prgenuav_in(here, &["check", invalid]).0, 1);
    assert_eq!(prgenuav_in(here, &["check", "nowhere.yaml"]).0, 2);

    assert!(
        doc.contains("Exit code 0: the flight ran to its end (landed or collision); 1: it did not (timeout, link lost, aborted, refused); 2: an error, also a vehicle too far from the test's home."),
        "fly's codes"
    );
    let (_, help, _) = prgenuav_in(here, &["--help"]);
    let help = help.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        help.contains("(exit 0: landed or collision; 1: the flight did not complete (timeout, link lost, aborted, refused by the vehicle); 2: an error, also a vehicle too far from the test's home)"),
        "{help}"
    );
    assert_eq!(prgenuav_in(here, &["fly", "nowhere.yaml"]).0, 2);
    assert_eq!(prgenuav_in(here, &["fly", valid, "--connect", "bogus:1"]).0, 2);

    assert!(
        doc.contains("the exit code is 0, or 2 for an error"),
        "generate's codes"
    );
    let (code, _, err) = prgenuav_in(here, &["generate", "nowhere.yaml", "2"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("nowhere.yaml") && err.matches("os error").count() <= 1,
        "{err}"
    );
    let (code, _, err) = prgenuav_in(here, &["generate", valid, "0"]);
    assert_eq!(code, 2, "{err}");
}

/// The first cells of the README's table of a campaign folder's files, one name each.
fn documented_files(readme: &str) -> Vec<String> {
    let text = std::fs::read_to_string(repo().join("README.md")).expect("README.md");
    let start = text.find("| file | content |").expect("the output folder's table");
    let table = text[start..].lines().skip(2).take_while(|l| l.starts_with('|'));
    let mut names = Vec::new();
    for row in table {
        let cell = row.split('|').nth(1).unwrap_or_default();
        names.extend(cell.split('`').skip(1).step_by(2).map(str::to_string));
    }
    assert!(readme.contains("holds (field by field"), "the table's introduction");
    names
}

#[test]
fn a_campaign_run_from_elsewhere_writes_every_documented_file() {
    let tmp = tempfile::tempdir().unwrap();
    let case = repo().join("missions/mission2.yaml");
    let args = ["generate", case.to_str().unwrap(), "6", "-s", "2", "-o", "out", "-q"];
    let (code, stdout, stderr) = prgenuav_in(tmp.path(), &args);
    assert_eq!(code, 0, "{stdout}{stderr}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 3, "{stdout}");
    assert!(
        lines[0].starts_with("2 failing tests (2 distinct at IoU 0.5) of 6 flights"),
        "{stdout}"
    );
    let folder = tmp
        .path()
        .join(lines[2].strip_prefix("output folder: ").expect("the folder line"));
    let name = folder.file_name().unwrap().to_string_lossy().into_owned();
    let iso = name.len() == 19
        && name.char_indices().all(|(i, c)| match i {
            4 | 7 | 13 | 16 => c == '-',
            10 => c == 'T',
            _ => c.is_ascii_digit(),
        });
    assert!(iso, "{name} is not YYYY-MM-DDTHH-MM-SS");

    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(folder.join("report.json")).unwrap()).unwrap();
    let unconfirmed = report["tests"]
        .as_array()
        .unwrap()
        .iter()
        .any(|t| t["confirmed"] == false);
    for documented in documented_files(&readme()) {
        if documented.contains("-K") || (documented.starts_with("unconfirmed") && !unconfirmed) {
            continue;
        }
        let file = documented.replace('N', "0").replace("roundR", "round0");
        assert!(
            folder.join(&file).exists(),
            "{file} (README: {documented}) not in {}",
            folder.display()
        );
    }
    let md = std::fs::read_to_string(folder.join("report.md")).unwrap();
    assert!(md.starts_with("# prgenuav campaign: "), "{md}");
    let reproduce = format!(
        "Reproduce: `prgenuav {}` (prgenuav {}",
        args.join(" "),
        env!("CARGO_PKG_VERSION")
    );
    assert!(md.contains(&reproduce), "{md}");
    assert!(md.find("## Failing tests") < md.find("## Appendix"), "{md}");
    // Resuming it says it is complete.
    let (code, _, err) = prgenuav_in(tmp.path(), &["generate", "--resume", folder.to_str().unwrap(), "-q"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("is complete: it flew its budget (6 of 6 flights)"),
        "{err}"
    );
    // The written test flies from anywhere: its files are named absolutely.
    let elsewhere = tempfile::tempdir().unwrap();
    let test = folder.join("test_0.yaml");
    let (code, out, err) = prgenuav_in(elsewhere.path(), &["check", test.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(!Path::new(&test).is_relative());
}
