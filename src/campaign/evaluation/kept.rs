//! What an evaluation keeps beside its journal (`evaluation/settings.json`): the settings its flights fly with
//! and what each test was when its first flight flew (its mission's positions and its parameters). A later run
//! of the same evaluation flies with the same settings (a fixed one asked otherwise is refused by name, as
//! `generate --resume` refuses one) and on the same tests (a test whose mission or parameters changed is
//! refused, naming it), so one test's runs never mix two modes, two vehicles or two missions.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::campaign::ground::error::CampaignError;
use crate::campaign::settings::evaluation::{EvaluationSettings, kept};
use crate::campaign::settings::resume::{refuse_conflicts, relaid};
use crate::campaign::settings::{CampaignSettings, Request};
use crate::model::safe_files::{MAX_READ_BYTES, read_capped_no_follow};
use crate::model::{ModelError, TestCase};

/// The file, inside the evaluation folder.
pub const KEPT_FILE: &str = "settings.json";
/// Its format.
const FORMAT: u64 = 1;

/// What a test was: its mission's positions (local metres about its home: x North, y East, z up) and its
/// PX4 parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KeptTest {
    /// The test's file.
    pub file: PathBuf,
    /// The positional mission items, in order.
    pub mission: Vec<[f64; 3]>,
    /// The PX4 parameters, in file order.
    pub params: Vec<(String, f64)>,
}

impl KeptTest {
    /// What `test` (read from `file`) is.
    pub fn of(file: &Path, test: &TestCase) -> Self {
        let mission = (test.mission.items.iter())
            .filter_map(|i| i.local.map(|p| [p.north_m, p.east_m, p.alt_m]))
            .collect();
        Self {
            file: file.to_path_buf(),
            mission,
            params: test.params.iter().map(|p| (p.name.clone(), p.value)).collect(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Kept {
    format: u64,
    settings: EvaluationSettings,
    tests: Vec<KeptTest>,
}

fn syntax(path: &Path, message: String) -> CampaignError {
    CampaignError::Model(ModelError::Syntax {
        path: path.to_path_buf(),
        line: None,
        column: None,
        message,
    })
}

/// What `folder` keeps, if it keeps anything (an evaluation begun before it kept its settings does not).
fn read(folder: &Path) -> Result<Option<Kept>, CampaignError> {
    let path = folder.join(KEPT_FILE);
    if std::fs::symlink_metadata(&path).is_err() {
        return Ok(None);
    }
    let bytes = read_capped_no_follow(&path, MAX_READ_BYTES)?;
    let kept: Kept =
        serde_json::from_slice(&bytes).map_err(|e| syntax(&path, format!("not an evaluation's settings: {e}")))?;
    if kept.format != FORMAT {
        return Err(syntax(
            &path,
            format!("format {}: this prgenuav reads format {FORMAT}", kept.format),
        ));
    }
    Ok(Some(kept))
}

/// The settings this run of the evaluation in `folder` flies with: `request` laid over what it kept (a fixed
/// setting asked otherwise refused), or, the first time, `request` over the suite's campaign settings.
pub fn settings(
    folder: &Path,
    request: &Request,
    suite: Option<&CampaignSettings>,
) -> Result<EvaluationSettings, CampaignError> {
    let config = |e: String| CampaignError::Config(e);
    let Some(kept_before) = read(folder)? else {
        return EvaluationSettings::resolve(request, suite).map_err(config);
    };
    let stored = serde_json::to_value(&kept_before.settings).map_err(|e| config(e.to_string()))?;
    let merged = relaid(&stored, request, kept).map_err(config)?;
    let settings = EvaluationSettings::resolve(&merged, None).map_err(config)?;
    let wanted = serde_json::to_value(&settings).map_err(|e| config(e.to_string()))?;
    refuse_conflicts(&stored, &wanted, request, &folder.join(KEPT_FILE)).map_err(config)?;
    Ok(settings)
}

/// Keeps `settings` and the `tests` in `folder` before their first flight, or refuses tests that changed
/// since the evaluation kept them. Written whole or not at all.
pub fn keep(folder: &Path, settings: &EvaluationSettings, tests: &[(PathBuf, TestCase)]) -> Result<(), CampaignError> {
    let now: Vec<KeptTest> = tests.iter().map(|(p, t)| KeptTest::of(p, t)).collect();
    if let Some(before) = read(folder)? {
        for (i, t) in now.iter().enumerate() {
            if let Some(b) = before.tests.get(i).filter(|b| *b != t) {
                return Err(CampaignError::Config(format!(
                    "{}: test {i} ({}) is not what its first flights flew ({}): its mission or parameters changed \
                     since; evaluate it into a fresh folder",
                    folder.join(KEPT_FILE).display(),
                    t.file.display(),
                    b.file.display()
                )));
            }
        }
    }
    let mut all = now;
    if let Some(before) = read(folder)?.filter(|b| b.tests.len() > all.len()) {
        // `--top` flies fewer tests than were kept: the others stay kept for a later run of them.
        all.extend(before.tests.into_iter().skip(all.len()));
    }
    let kept = Kept {
        format: FORMAT,
        settings: settings.clone(),
        tests: all,
    };
    Ok(crate::io::write_json(&folder.join(KEPT_FILE), &kept, true)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bridge::FlyMode;
    use crate::campaign::settings::{Loaded, find};

    fn request(flags: &[(&str, &str, &str)]) -> Request {
        let flags: Vec<_> = (flags.iter())
            .map(|(s, k, v)| {
                let s = find(s, k).unwrap();
                (s, (s.parse)(v).unwrap())
            })
            .collect();
        Request::new(&Loaded::default(), &flags).unwrap()
    }

    fn test(name: &str) -> (PathBuf, TestCase) {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("missions").join(name);
        let t = TestCase::load(&path).unwrap();
        (path, t)
    }

    #[test]
    fn a_campaigns_folder_is_evaluated_in_the_campaigns_mode_and_a_later_run_keeps_it() {
        let dir = tempfile::tempdir().unwrap();
        let mut suite = crate::campaign::settings::test_settings(Path::new("/m.yaml"), 10);
        suite.campaign.mode = FlyMode::CollisionPrevention;
        let first = settings(dir.path(), &request(&[]), Some(&suite)).unwrap();
        assert_eq!(first.campaign.mode, FlyMode::CollisionPrevention);
        keep(dir.path(), &first, &[test("mission2.yaml")]).unwrap();
        // A later run without the suite's campaign.json still flies what the evaluation kept.
        let again = settings(dir.path(), &request(&[]), None).unwrap();
        assert_eq!(again, first);
        let e = settings(dir.path(), &request(&[("campaign", "mode", "avoidance")]), None)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("--mode avoidance conflicts with mode collision-prevention stored in")
                && e.contains(KEPT_FILE),
            "{e}"
        );
        let e = settings(
            dir.path(),
            &request(&[("vehicles", "connect", "udpin:0.0.0.0:14540")]),
            None,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("--connect udpin:0.0.0.0:14540 conflicts with connect mock"),
            "{e}"
        );
        let more = request(&[("mock", "vehicles", "1")]);
        assert_eq!(
            settings(dir.path(), &more, None).unwrap().mock.vehicles,
            1,
            "asked again, not kept"
        );
    }

    #[test]
    fn a_test_whose_mission_changed_since_its_first_flights_is_refused_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let s = EvaluationSettings::resolve(&request(&[]), None).unwrap();
        keep(dir.path(), &s, &[test("mission2.yaml"), test("mission3.yaml")]).unwrap();
        keep(dir.path(), &s, &[test("mission2.yaml")]).unwrap();
        let e = keep(dir.path(), &s, &[test("mission3.yaml")]).unwrap_err().to_string();
        assert!(
            e.contains("test 0") && e.contains("mission3.yaml") && e.contains("changed"),
            "{e}"
        );
        // `--top 1` kept the second test for a later run of both.
        keep(dir.path(), &s, &[test("mission2.yaml"), test("mission3.yaml")]).unwrap();
    }
}
