//! What a campaign is asked for: the campaign TOML with the flags laid over it (a flag replaces its key), typed
//! once by serde into [`Asked`], every key optional; and which settings were given, and where, so a resumed
//! campaign can name what it refuses.

pub use super::asked::Asked;
use super::file::Loaded;
use super::{Setting, all};
use crate::generator::GeneratorConfig;

/// A setting given explicitly, by a flag or by the TOML file.
#[derive(Debug, Clone)]
pub struct Given {
    /// The setting.
    pub setting: &'static Setting,
    /// The TOML file that gave it (`None`: the command line).
    pub file: Option<String>,
}

impl Given {
    /// How the user asked for it, with `value` as typed: `--seed 3`, `--no-learn`, `CASE m.yaml`, or
    /// `screening.threshold_m = 2 in c.toml`.
    pub fn asked(&self, value: &str) -> String {
        let s = self.setting;
        match (&self.file, &s.flag) {
            (Some(file), _) => format!("{} = {value} in {file}", s.toml_key()),
            (None, Some(f)) if f.is_switch() => f.long.to_string(),
            (None, Some(f)) if f.position.is_some() => format!("{} {value}", f.value_name),
            (None, Some(f)) => format!("{} {value}", f.long),
            (None, None) => format!("{} {value}", s.toml_key()),
        }
    }
}

/// What the command line and the TOML file ask for.
#[derive(Debug, Clone, Default)]
pub struct Request {
    /// Every section, flags laid over the file.
    pub asked: Asked,
    /// The settings given, in declaration order.
    pub given: Vec<Given>,
}

impl Request {
    /// The flags given (each with its key's TOML value) laid over `file`: a flag replaces its key. Each flag's
    /// value is checked against its declared range and choices first, so the error names the flag.
    pub fn new(file: &Loaded, flags: &[(&'static Setting, toml::Value)]) -> Result<Self, String> {
        let mut raw = file.raw.clone();
        let mut given = Vec::new();
        for s in all() {
            let flag = flags.iter().find(|(f, _)| f.section == s.section && f.key == s.key);
            if let Some((_, v)) = flag {
                super::check::check_value(s, &serde_json::to_value(v).map_err(|e| e.to_string())?)?;
                let section = raw
                    .entry(s.section)
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()));
                let table = section
                    .as_table_mut()
                    .ok_or_else(|| format!("{}: [{}] is not a section", file.name(), s.section))?;
                table.insert(s.key.to_string(), v.clone());
                given.push(Given { setting: s, file: None });
            } else if file.sets(s.section, s.key) {
                given.push(Given {
                    setting: s,
                    file: Some(file.name()),
                });
            }
        }
        let asked = Asked::typed(&raw).map_err(|e| match &file.path {
            Some(_) => format!("{} (with the flags given): {e}", file.name()),
            None => e,
        })?;
        Ok(Self { asked, given })
    }

    /// Whether `section.key` was given.
    pub fn gives(&self, section: &str, key: &str) -> bool {
        self.given
            .iter()
            .any(|g| g.setting.section == section && g.setting.key == key)
    }

    /// The paths asked for made absolute against the working folder, so `campaign.json` names them from any
    /// folder: the case and the prior as spelled (not resolved through links), the PX4 build resolved.
    pub fn make_paths_absolute(&mut self) -> Result<(), String> {
        let absolute = |p: &std::path::Path| {
            std::path::absolute(p).map_err(|e| format!("{}: cannot make the path absolute: {e}", p.display()))
        };
        let c = &mut self.asked.campaign;
        if let Some(case) = &c.case {
            c.case = Some(absolute(case)?);
        }
        if let Some(prior) = &c.prior {
            c.prior = Some(absolute(prior)?);
        }
        if let Some(build) = &self.asked.vehicles.px4 {
            self.asked.vehicles.px4 = Some(std::fs::canonicalize(build).unwrap_or_else(|_| build.clone()));
        }
        Ok(())
    }

    /// The generator's configuration asked for: its defaults under the file's keys and the flags.
    pub fn generator(&self) -> GeneratorConfig {
        self.asked.generator.clone().unwrap_or_default()
    }
}

impl Request {
    /// Checks the settings given that only make sense with another one (the PX4 instances' settings without
    /// `--px4`, the runner's without `--runner`, `--jobs` where each URL flies one flight at a time).
    pub fn check(&self) -> Result<(), String> {
        let v = &self.asked.vehicles;
        let given = |k| self.gives("vehicles", k);
        if v.px4.is_none() && (given("instances") || given("speed_factor") || given("keep_ulog")) {
            return Err("--instances, --speed-factor and --keep-ulog need --px4 BUILD_DIR".into());
        }
        if v.px4.is_none() && (given("sim") || given("sim_link") || given("bench")) {
            return Err(
                "--sim, --sim-link and --bench say how the --px4 instances are simulated: they need --px4 \
                        BUILD_DIR"
                    .into(),
            );
        }
        if v.hitl.is_some() && (v.runner.is_some() || v.connect.as_ref().is_some_and(|c| c != &["mock"])) {
            return Err("--hitl boards are the vehicles: not with --runner or --connect".into());
        }
        if v.hitl.is_some() && v.jobs.is_some() {
            return Err(
                "--jobs: each --hitl board flies one flight at a time; give more boards for more at once".into(),
            );
        }
        if v.runner.is_none() && (given("job_timeout_s") || given("runner_cancel")) {
            return Err("--job-timeout and --runner-cancel go with --runner".into());
        }
        if let (Some(j), Some(k)) = (v.jobs, v.instances)
            && j != k
        {
            return Err(format!("--jobs {j} and --instances {k} disagree: give one"));
        }
        let links = v.runner.is_none() && v.px4.is_none() && v.connect.as_ref().is_some_and(|c| c != &["mock"]);
        if links && v.jobs.is_some() {
            return Err(
                "--jobs: with --connect URLs each URL flies one flight at a time; give more URLs for more at once"
                    .into(),
            );
        }
        match (v.jobs, v.runner.is_some(), self.on_mock_by_jobs()) {
            (Some(n), true, _) => {
                super::keys::RUNNER_JOBS.check("--jobs", n as f64)?;
            }
            (Some(n), false, true) => {
                // `--jobs` on the embedded mocks has the range of `mock.vehicles`.
                if let Some(limit) = super::find("mock", "vehicles").and_then(|s| s.range) {
                    limit.check("--jobs on the embedded mocks", n as f64)?;
                }
            }
            (Some(0), ..) => return Err("--jobs 0 is out of range: 1 or more".into()),
            _ => {}
        }
        Ok(())
    }

    /// `--jobs` sets the number of embedded mocks (no `--mock-vehicles` given, the mocks fly).
    fn on_mock_by_jobs(&self) -> bool {
        let v = &self.asked.vehicles;
        v.runner.is_none()
            && v.px4.is_none()
            && v.hitl.is_none()
            && v.connect() == ["mock"]
            && !self.gives("mock", "vehicles")
    }
}
