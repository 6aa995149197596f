//! The competition's recorded flights (the JSON format of `hfs-flights/`) read as cases: mission, obstacles,
//! PX4 parameters and the minimum distance each tier's ground truth gives.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::model::competition::{HALF_VEHICLE_WIDTH_M, MISSION_PARAMS};
use crate::model::{GeoPoint, LocalPoint, Mission, MissionItem, Obstacle, Param, Position, SIM_HOME, Size};

/// Box height used where a flight did not record it (above the 10 m flight altitude, as the rules require).
pub const DEFAULT_HEIGHT_M: f64 = 15.0;

/// Why a flight file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum FidelityError {
    /// File or folder cannot be read.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not a flight JSON of the expected format.
    #[error("{path}: {message}")]
    Format {
        /// The path.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// One recorded flight, ready to simulate.
#[derive(Debug, Clone)]
pub struct FlightCase {
    /// `id` of the file.
    pub id: String,
    /// Tier letter (`A`, `B`, `C`).
    pub tier: String,
    /// Mission name (`mission1`..).
    pub mission_name: String,
    /// The mission, local positions from the file's waypoints.
    pub mission: Mission,
    /// The obstacles.
    pub obstacles: Vec<Obstacle>,
    /// PX4 parameters of the flight (the competition's `mission-params.csv` where the file names it).
    pub params: Vec<Param>,
    /// The real minimum distance, metres, in the tier's definition.
    pub real_m: f64,
    /// Metres to subtract from a centre-line prediction to match the tier's definition.
    pub definition_offset_m: f64,
    /// Identical obstacle sets flown more than once share a group.
    pub repeat_group: Option<String>,
}

/// The competition's `mission-params.csv` ([`MISSION_PARAMS`]), for flights that did not record theirs.
pub fn competition_params() -> Vec<Param> {
    MISSION_PARAMS
        .into_iter()
        .map(|(n, v)| Param {
            name: n.into(),
            value: v,
        })
        .collect()
}

fn num(v: &Value) -> Option<f64> {
    v.as_f64().filter(|x| x.is_finite())
}

/// Reads one flight file; `Ok(None)` if it has no obstacles or no recorded distance (nothing to compare).
pub fn load_flight(path: &Path) -> Result<Option<FlightCase>, FidelityError> {
    let text = std::fs::read_to_string(path).map_err(|source| FidelityError::Io {
        path: path.into(),
        source,
    })?;
    let bad = |m: &str| format_error(path, m);
    let doc: Value = serde_json::from_str(&text).map_err(|e| bad(&format!("not JSON: {e}")))?;
    let id = doc["id"].as_str().ok_or_else(|| bad("missing id"))?.to_string();
    let tier = doc["tier"].as_str().ok_or_else(|| bad("missing tier"))?;
    let tier = tier.get(..1).unwrap_or("?").to_string();
    let mission = flight_mission(&doc, path)?;
    let obstacles = flight_obstacles(&doc, path)?;
    let real = num(&doc["hfs_min_distance_aerialist"]).or_else(|| num(&doc["hfs_min_distance_digitized"]));
    let Some(real_m) = real else { return Ok(None) };
    if obstacles.is_empty() {
        return Ok(None);
    }
    let params = match doc["drone_params"].as_object() {
        Some(m) => m
            .iter()
            .filter_map(|(k, v)| num(v).map(|value| Param { name: k.clone(), value }))
            .collect(),
        None => competition_params(),
    };
    // Group numbers are per source (the id's prefix).
    let repeat_group = doc["repeat_group"]
        .as_u64()
        .map(|g| format!("{}#{g}", id.rsplit_once('_').map_or(id.as_str(), |p| p.0)));
    Ok(Some(FlightCase {
        id,
        definition_offset_m: if tier == "B" { HALF_VEHICLE_WIDTH_M } else { 0.0 },
        tier,
        mission_name: doc["mission"]["name"].as_str().unwrap_or("?").to_string(),
        mission,
        obstacles,
        params,
        real_m,
        repeat_group,
    }))
}

fn format_error(path: &Path, message: &str) -> FidelityError {
    FidelityError::Format {
        path: path.into(),
        message: message.into(),
    }
}

/// The flight's `mission.waypoints` as a mission from the simulator's home.
fn flight_mission(doc: &Value, path: &Path) -> Result<Mission, FidelityError> {
    let wps = doc["mission"]["waypoints"]
        .as_array()
        .ok_or_else(|| format_error(path, "missing mission.waypoints"))?;
    let items = wps
        .iter()
        .map(|w| flight_item(w).ok_or_else(|| format_error(path, "waypoint without cmd")))
        .collect::<Result<Vec<_>, _>>()?;
    if !items.iter().any(|i| i.local.is_some()) {
        return Err(format_error(path, "the mission has no positional waypoint"));
    }
    Ok(Mission {
        items,
        planned_home: None,
        home: SIM_HOME,
        source: path.into(),
    })
}

/// One waypoint: its command, and its local (`x` North, `y` East, `z` altitude, metres) and global positions
/// where given; `None` without a command.
fn flight_item(w: &Value) -> Option<MissionItem> {
    let cmd = w["cmd"].as_u64().filter(|c| *c <= u64::from(u16::MAX))?;
    let local = match (num(&w["x"]), num(&w["y"]), num(&w["z"])) {
        (Some(n), Some(e), Some(a)) => Some(LocalPoint {
            north_m: n,
            east_m: e,
            alt_m: a,
        }),
        _ => None,
    };
    let global = match (num(&w["lat"]), num(&w["lon"])) {
        (Some(lat), Some(lon)) => Some(GeoPoint {
            lat_deg: lat,
            lon_deg: lon,
            alt_m: local.map_or(0.0, |l| l.alt_m),
        }),
        _ => None,
    };
    Some(MissionItem {
        command: cmd as u16,
        frame: w["frame"].as_u64().unwrap_or(3).min(255) as u8,
        params: [None; 7],
        auto_continue: true,
        global,
        local,
    })
}

/// The flight's boxes (metres, degrees); a missing height is [`DEFAULT_HEIGHT_M`], missing `z` and `r` are 0.
fn flight_obstacles(doc: &Value, path: &Path) -> Result<Vec<Obstacle>, FidelityError> {
    let list = doc["obstacles"]
        .as_array()
        .ok_or_else(|| format_error(path, "missing obstacles"))?;
    let mut obstacles = Vec::new();
    for o in list {
        let f = |k: &str| num(&o[k]);
        let (Some(l), Some(w), Some(x), Some(y)) = (f("l"), f("w"), f("x"), f("y")) else {
            return Err(format_error(path, "obstacle without l, w, x or y"));
        };
        obstacles.push(Obstacle {
            size: Size {
                l,
                w,
                h: f("h").unwrap_or(DEFAULT_HEIGHT_M),
            },
            position: Position {
                x,
                y,
                z: f("z").unwrap_or(0.0),
                r: f("r").unwrap_or(0.0),
            },
        });
    }
    Ok(obstacles)
}

/// Reads every `*.json` flight of `dir` (sorted by name); returns the usable cases and the skipped file names.
pub fn load_dir(dir: &Path) -> Result<(Vec<FlightCase>, Vec<String>), FidelityError> {
    let io = |source| FidelityError::Io {
        path: dir.into(),
        source,
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    let (mut cases, mut skipped) = (Vec::new(), Vec::new());
    for f in files {
        match load_flight(&f)? {
            Some(c) => cases.push(c),
            None => skipped.push(
                f.file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
            ),
        }
    }
    Ok((cases, skipped))
}
