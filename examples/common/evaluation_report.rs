//! The examples that read evaluated campaign folders: their arguments and `evaluation/report.json`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::Context;

/// Each evaluated test's JSON (from `evaluation/report.json`) by its YAML's file name; `None` when the folder
/// has no evaluation.
pub fn evaluated_tests(folder: &Path) -> anyhow::Result<Option<HashMap<String, serde_json::Value>>> {
    let path = folder.join("evaluation/report.json");
    if !path.exists() {
        return Ok(None);
    }
    tests_by_name(&read_report(&path)?).map(Some)
}

/// An evaluation's `report.json`.
pub fn read_report(path: &Path) -> anyhow::Result<serde_json::Value> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}", path.display()))
}

/// A report's `tests[]` by each test YAML's file name.
pub fn tests_by_name(report: &serde_json::Value) -> anyhow::Result<HashMap<String, serde_json::Value>> {
    let tests = report["tests"].as_array().context("evaluation: no tests[]")?;
    let named = tests.iter().filter_map(|t| {
        let name = t["test"].as_str().and_then(|p| Path::new(p).file_name()?.to_str())?;
        Some((name.to_string(), t.clone()))
    });
    Ok(named.collect())
}

/// The campaign folders named on the command line; at least one, or the usage of `example`.
pub fn campaign_folders(example: &str) -> anyhow::Result<Vec<PathBuf>> {
    let folders: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    anyhow::ensure!(!folders.is_empty(), "usage: {example} CAMPAIGN...");
    Ok(folders)
}
