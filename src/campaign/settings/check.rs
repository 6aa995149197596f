//! The one check of a campaign's settings, before anything is drawn, started or flown: every value against its
//! declared range (both ends of a `{min, max}` range) and choices, naming the flag and the TOML key; and the
//! settings that must agree with each other.

use serde_json::Value;

use super::stored::{Backend, CampaignSettings};
use super::{Setting, all};

/// Checks `v`, the value of `s`, against its declared range and choices.
pub fn check_value(s: &Setting, v: &Value) -> Result<(), String> {
    if let Some(limit) = &s.range {
        let numbers: Vec<f64> = match v {
            Value::Object(o) => ["min", "max"].iter().filter_map(|k| o.get(*k)?.as_f64()).collect(),
            other => other.as_f64().into_iter().collect(),
        };
        for n in numbers {
            limit.check(&s.names(), n)?;
        }
    }
    let choices = (s.choices)();
    if let (false, Some(name)) = (choices.is_empty(), v.as_str())
        && !choices.iter().any(|(c, _)| *c == name)
    {
        let names: Vec<&str> = choices.iter().map(|(c, _)| *c).collect();
        return Err(format!("{} {name:?} is not one of {}", s.names(), names.join(", ")));
    }
    Ok(())
}

/// The value at a dotted `key` of a JSON object.
pub fn at<'a>(v: &'a Value, key: &str) -> Option<&'a Value> {
    key.split('.').try_fold(v, |v, k| v.get(k))
}

impl CampaignSettings {
    /// Checks every setting against its declaration and the settings that must agree; the campaign runs
    /// nothing else.
    pub fn check(&self) -> Result<(), String> {
        let json = serde_json::to_value(self).map_err(|e| e.to_string())?;
        for s in all() {
            if let Some(v) = at(&json, &s.toml_key()).filter(|v| !v.is_null()) {
                check_value(s, v)?;
            }
        }
        self.check_vehicles()?;
        if self.campaign.prior.is_some() && !self.learns() {
            return Err("--prior needs a learning campaign (the settings turn learning off)".into());
        }
        Ok(())
    }

    fn check_vehicles(&self) -> Result<(), String> {
        let v = &self.vehicles;
        if v.runner.is_some() && v.px4.is_some() {
            return Err(
                "--runner and --px4 are two ways to fly: give one (a runner's command may start PX4 itself)".into(),
            );
        }
        if let Some(why) = v.bench.sim_refusal(v.sim) {
            return Err(why);
        }
        if v.sim_link == crate::bridge::SimLink::Serial && v.sim != crate::bridge::VehicleSim::Iris {
            return Err("--sim-link serial is the link of prgenuav's simulator: give --sim iris too".into());
        }
        if let Some(boards) = &v.hitl {
            if boards.is_empty() {
                return Err("--hitl names no board".into());
            }
            for b in boards {
                crate::bridge::hil::board::BoardPort::parse(b)?;
            }
        }
        if v.connect.is_empty() {
            return Err("--connect names no vehicle".into());
        }
        if v.connect.len() > 1 && v.connect.iter().any(|u| u == "mock") {
            return Err("--connect takes either `mock` or MAVLink URLs, not both".into());
        }
        // Before anything is screened or flown: a typo in the fifth URL must not cost the first four flights.
        if let Backend::Links(urls) = self.backend() {
            for url in urls {
                crate::bridge::LinkAddress::parse(url).map_err(|e| format!("--connect: {e}"))?;
            }
        }
        if self.backend() == Backend::Mock && v.jobs.is_some_and(|j| j != self.mock.vehicles) {
            return Err(format!(
                "--jobs {} and --mock-vehicles (mock.vehicles) {} disagree: give one",
                v.jobs.unwrap_or_default(),
                self.mock.vehicles
            ));
        }
        Ok(())
    }
}
