//! A case study or generated test: Aerialist's YAML, in both its old and new key spellings.

use std::path::{Path, PathBuf};

use serde_json::{Map, Value};

use super::error::{ModelError, Result};
use super::fields::{
    FieldError, FieldResult, as_map, describe, fail, join, known_keys, number, opt_number, opt_string, req_number,
};
use super::files::read_text;
use super::mission::Mission;
use super::obstacle::{Obstacle, Position, Size};
use super::references::resolve;
use super::tables::{Command, Param, command_from, parse_commands_csv, parse_params_csv};
use geodesy::{GeoPoint, SIM_HOME};

/// Which key names a YAML uses: `drone`/`test` (Aerialist before 2025-09) or `robot`/`mission` (since).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Spelling {
    /// `drone:` and `test:`.
    Old,
    /// `robot:` and `mission:` (written by default).
    #[default]
    New,
}

impl Spelling {
    fn vehicle_key(self) -> &'static str {
        match self {
            Spelling::Old => "drone",
            Spelling::New => "robot",
        }
    }
    fn commands_key(self) -> &'static str {
        match self {
            Spelling::Old => "test",
            Spelling::New => "mission",
        }
    }
}

const TOP_KEYS: [&str; 7] = ["drone", "robot", "simulation", "test", "mission", "assertion", "agent"];
const VEHICLE_KEYS: [&str; 4] = ["port", "params", "params_file", "mission_file"];
const SIM_KEYS: [&str; 7] = [
    "simulator",
    "world",
    "speed",
    "headless",
    "obstacles",
    "home_position",
    "wind",
];
const COMMAND_KEYS: [&str; 3] = ["commands", "commands_file", "speed"];

/// A test: the case study (mission, params, commands) plus the obstacles placed for it.
///
/// Obstacles are in Aerialist's frame (local NED on the ground, `x` North, `y` East, `r` degrees). The mission's
/// local positions are projected about [`TestCase::home`]: `simulation.home_position` when the YAML sets it,
/// otherwise the competition simulator's default home [`SIM_HOME`], because that is where PX4 SITL puts its
/// local origin; the bridge records and judges flights in the local frame about this home.
#[derive(Debug, Clone, PartialEq)]
pub struct TestCase {
    /// The YAML file it was read from.
    pub path: PathBuf,
    /// The key spelling it was read with.
    pub spelling: Spelling,
    /// The whole document, so blocks we do not interpret (`assertion`, `agent`, `wind`) are written back.
    pub document: Map<String, Value>,
    /// `drone.port` (`ros`, `sitl`, `cf`, or a number).
    pub port: Option<String>,
    /// PX4 parameters, from `params` or `params_file`, in file order.
    pub params: Vec<Param>,
    /// `mission_file` as written in the YAML.
    pub mission_file: String,
    /// The mission, loaded.
    pub mission: Mission,
    /// The projection home (see the type's documentation).
    pub home: GeoPoint,
    /// The obstacles (`simulation.obstacles`).
    pub obstacles: Vec<Obstacle>,
    /// The commands, from `commands` or `commands_file`.
    pub commands: Vec<Command>,
}

impl TestCase {
    /// Reads a case study or test YAML and everything it refers to.
    pub fn load(path: &Path) -> Result<Self> {
        let text = read_text(path)?;
        Self::parse(&text, path)
    }

    /// Parses YAML text; relative file names resolve as `resolve` says: the working folder, then `path`'s
    /// folder and its parents.
    pub fn parse(text: &str, path: &Path) -> Result<Self> {
        let document = document_of(text, path)?;
        let field_err = |e: FieldError| ModelError::field(path, e.field, e.message);
        known_keys(&document, "", &TOP_KEYS).map_err(field_err)?;
        let spelling = spelling_of(&document).map_err(field_err)?;
        let vkey = spelling.vehicle_key();
        let vehicle = as_map(document.get(vkey).unwrap_or(&Value::Null), vkey).map_err(field_err)?;
        known_keys(vehicle, vkey, &VEHICLE_KEYS).map_err(field_err)?;
        let port = opt_string(vehicle, vkey, "port").map_err(field_err)?;

        let (home, obstacles) = parse_simulation(&document).map_err(field_err)?;

        let base = path.parent().unwrap_or(Path::new("."));
        let mission_file = opt_string(vehicle, vkey, "mission_file")
            .map_err(field_err)?
            .ok_or_else(|| {
                field_err(FieldError {
                    field: join(vkey, "mission_file"),
                    message: "missing".into(),
                })
            })?;
        let mission_path =
            resolve(base, &mission_file).map_err(|m| ModelError::field(path, join(vkey, "mission_file"), m))?;
        let mission = Mission::load(&mission_path, home)?;
        let params = parse_params(vehicle, vkey, base, path)?;

        let ckey = spelling.commands_key();
        let commands = match document.get(ckey) {
            None | Some(Value::Null) => Vec::new(),
            Some(v) => {
                let map = as_map(v, ckey).map_err(field_err)?;
                known_keys(map, ckey, &COMMAND_KEYS).map_err(field_err)?;
                parse_commands(map, ckey, base, path)?
            }
        };
        Ok(Self {
            path: path.to_path_buf(),
            spelling,
            document,
            port,
            params,
            mission_file,
            mission,
            home,
            obstacles,
            commands,
        })
    }

    /// The test as YAML in `spelling`, with [`TestCase::obstacles`] as `simulation.obstacles`.
    ///
    /// Every other block is written back as it was read (file references stay references).
    pub fn to_yaml(&self, spelling: Spelling) -> String {
        let mut doc = Map::new();
        for (key, value) in &self.document {
            let key = match key.as_str() {
                "drone" | "robot" => spelling.vehicle_key(),
                "test" | "mission" => spelling.commands_key(),
                k => k,
            };
            doc.insert(key.to_string(), value.clone());
        }
        let sim = doc.entry("simulation").or_insert_with(|| Value::Object(Map::new()));
        if !sim.is_object() {
            *sim = Value::Object(Map::new());
        }
        if let Value::Object(sim) = sim {
            if self.obstacles.is_empty() {
                sim.remove("obstacles");
            } else {
                sim.insert("obstacles".into(), serde_json::json!(self.obstacles));
            }
        }
        // Serialising a JSON value tree cannot fail: it has only strings, numbers, booleans, lists and maps.
        serde_saphyr::to_string(&Value::Object(doc)).unwrap_or_default()
    }

    /// Writes [`TestCase::to_yaml`] to `path` atomically (a temporary file, then a rename).
    pub fn save(&self, path: &Path, spelling: Spelling) -> Result<()> {
        super::files::write_atomic(path, self.to_yaml(spelling).as_bytes())
    }

    /// A copy whose file references are absolute paths, so the test YAML written from it loads from any
    /// working folder, in prgenuav and in Aerialist alike.
    pub fn with_absolute_references(&self) -> Result<Self> {
        let mut out = self.clone();
        if let Some(mission_file) = super::references::make_absolute(&mut out.document, &self.path)? {
            out.mission_file = mission_file;
        }
        Ok(out)
    }

    /// A copy with other obstacles.
    pub fn with_obstacles(&self, obstacles: Vec<Obstacle>) -> Self {
        Self {
            obstacles,
            ..self.clone()
        }
    }
}

fn yaml_error(path: &Path, e: &serde_saphyr::Error) -> ModelError {
    let loc = e.location();
    let (line, column) = match loc {
        Some(l) => (Some(l.line() as usize), Some(l.column() as usize)),
        None => (None, None),
    };
    ModelError::Syntax {
        path: path.to_path_buf(),
        line,
        column,
        message: format!("not valid YAML: {e}"),
    }
}

fn spelling_of(doc: &Map<String, Value>) -> FieldResult<Spelling> {
    let old = doc.contains_key("drone") || doc.contains_key("test");
    let new = doc.contains_key("robot") || doc.contains_key("mission");
    match (old, new) {
        (true, true) => fail(
            "(document)",
            "mixes `drone`/`test` with `robot`/`mission`; use one spelling",
        ),
        (_, true) => Ok(Spelling::New),
        (true, false) => Ok(Spelling::Old),
        (false, false) => fail(
            "drone",
            "missing (a case study needs `drone:` or `robot:` with a mission_file)",
        ),
    }
}

fn parse_home(sim: &Map<String, Value>) -> FieldResult<GeoPoint> {
    let field = "simulation.home_position";
    match sim.get("home_position") {
        None | Some(Value::Null) => Ok(SIM_HOME),
        Some(Value::Array(v)) if v.len() == 3 => {
            let lat = number(&v[0], &format!("{field}[0]"))?;
            let lon = number(&v[1], &format!("{field}[1]"))?;
            let alt = number(&v[2], &format!("{field}[2]"))?;
            if !(-90.0..=90.0).contains(&lat) || !(-180.0..=180.0).contains(&lon) {
                return fail(field, format!("[{lat}, {lon}] is not a latitude/longitude in degrees"));
            }
            Ok(GeoPoint {
                lat_deg: lat,
                lon_deg: lon,
                alt_m: alt,
            })
        }
        Some(v) => fail(field, format!("expected [lat, lon, alt], got {}", describe(v))),
    }
}

fn parse_obstacles(sim: &Map<String, Value>) -> FieldResult<Vec<Obstacle>> {
    let list = match sim.get("obstacles") {
        None | Some(Value::Null) => return Ok(Vec::new()),
        Some(Value::Array(list)) => list,
        Some(v) => return fail("simulation.obstacles", format!("expected a list, got {}", describe(v))),
    };
    list.iter()
        .enumerate()
        .map(|(i, o)| {
            let base = format!("simulation.obstacles[{i}]");
            let o = as_map(o, &base)?;
            known_keys(o, &base, &["size", "position", "shape"])?;
            if let Some(shape) = o.get("shape")
                && shape.as_str() != Some("box")
            {
                return fail(
                    &join(&base, "shape"),
                    format!("only \"box\" is supported, got {}", describe(shape)),
                );
            }
            let sb = join(&base, "size");
            let size = as_map(o.get("size").unwrap_or(&Value::Null), &sb)?;
            known_keys(size, &sb, &["l", "w", "h"])?;
            let pb = join(&base, "position");
            let pos = as_map(o.get("position").unwrap_or(&Value::Null), &pb)?;
            known_keys(pos, &pb, &["x", "y", "z", "r"])?;
            Ok(Obstacle {
                size: Size {
                    l: req_number(size, &sb, "l")?,
                    w: req_number(size, &sb, "w")?,
                    h: req_number(size, &sb, "h")?,
                },
                position: Position {
                    x: req_number(pos, &pb, "x")?,
                    y: req_number(pos, &pb, "y")?,
                    z: opt_number(pos, &pb, "z")?.unwrap_or(0.0),
                    r: opt_number(pos, &pb, "r")?.unwrap_or(0.0),
                },
            })
        })
        .collect()
}

fn parse_params(vehicle: &Map<String, Value>, vkey: &str, base: &Path, path: &Path) -> Result<Vec<Param>> {
    let err = |e: FieldError| ModelError::field(path, e.field, e.message);
    if let Some(v) = vehicle.get("params").filter(|v| !v.is_null()) {
        let field = join(vkey, "params");
        let map = as_map(v, &field).map_err(err)?;
        return map
            .iter()
            .map(|(k, v)| {
                Ok(Param {
                    name: k.clone(),
                    value: number(v, &join(&field, k)).map_err(err)?,
                })
            })
            .collect();
    }
    match opt_string(vehicle, vkey, "params_file").map_err(err)? {
        None => Ok(Vec::new()),
        Some(name) => {
            let file = resolve(base, &name).map_err(|m| ModelError::field(path, join(vkey, "params_file"), m))?;
            parse_params_csv(&read_text(&file)?, &file)
        }
    }
}

fn parse_commands(map: &Map<String, Value>, ckey: &str, base: &Path, path: &Path) -> Result<Vec<Command>> {
    let err = |e: FieldError| ModelError::field(path, e.field, e.message);
    if let Some(v) = map.get("commands").filter(|v| !v.is_null()) {
        let field = join(ckey, "commands");
        let list = v
            .as_array()
            .ok_or_else(|| ModelError::field(path, &field, format!("expected a list, got {}", describe(v))))?;
        return list
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let f = format!("{field}[{i}]");
                let m = as_map(c, &f).map_err(err)?;
                known_keys(m, &f, &["timestamp", "mode", "x", "y", "z", "r"]).map_err(err)?;
                let get = |k: &str, default: f64| opt_number(m, &f, k).map(|v| v.unwrap_or(default)).map_err(err);
                let v = [
                    get("timestamp", 0.0)?,
                    req_number(m, &f, "mode").map_err(err)?,
                    get("x", 0.0)?,
                    get("y", 0.0)?,
                    get("z", 0.5)?,
                    get("r", 0.0)?,
                ];
                command_from(v).map_err(|msg| ModelError::field(path, &f, msg))
            })
            .collect();
    }
    match opt_string(map, ckey, "commands_file").map_err(err)? {
        None => Ok(Vec::new()),
        Some(name) => {
            let file = resolve(base, &name).map_err(|m| ModelError::field(path, join(ckey, "commands_file"), m))?;
            parse_commands_csv(&read_text(&file)?, &file)
        }
    }
}

/// The YAML document's top-level mapping, or an error naming what it is instead.
fn document_of(text: &str, path: &Path) -> Result<Map<String, Value>> {
    let value: Value = serde_saphyr::from_str(text).map_err(|e| yaml_error(path, &e))?;
    match value {
        Value::Object(m) => Ok(m),
        Value::Null => Err(ModelError::field(
            path,
            "(document)",
            "empty; expected a case-study mapping",
        )),
        other => Err(ModelError::field(
            path,
            "(document)",
            format!("expected a mapping, got {}", describe(&other)),
        )),
    }
}

/// The `simulation` block (absent or null: the defaults): its home and obstacles, its speed checked.
fn parse_simulation(document: &Map<String, Value>) -> std::result::Result<(GeoPoint, Vec<Obstacle>), FieldError> {
    let sim_empty = Map::new();
    let sim = match document.get("simulation") {
        None | Some(Value::Null) => &sim_empty,
        Some(v) => as_map(v, "simulation")?,
    };
    known_keys(sim, "simulation", &SIM_KEYS)?;
    let home = parse_home(sim)?;
    let obstacles = parse_obstacles(sim)?;
    if let Some(speed) = opt_number(sim, "simulation", "speed")?
        && speed <= 0.0
    {
        return Err(FieldError {
            field: "simulation.speed".into(),
            message: format!("{speed} is not positive"),
        });
    }
    Ok((home, obstacles))
}
