//! A PX4 mission from a QGroundControl `.plan` file, with local positions for every positional item.

use std::path::{Path, PathBuf};

use num_traits::FromPrimitive;
use serde_json::Value;

use super::error::{ModelError, Result};
use super::files::read_text;
use geodesy::{GeoPoint, LocalProjection};

/// MAV_CMD_NAV_WAYPOINT.
pub const CMD_WAYPOINT: u16 = 16;
/// MAV_CMD_NAV_LAND.
pub const CMD_LAND: u16 = 21;
/// MAV_CMD_NAV_TAKEOFF.
pub const CMD_TAKEOFF: u16 = 22;

/// Commands that carry a position PX4 flies to (waypoints, loiters, takeoff, land, VTOL variants).
const POSITIONAL: [u16; 10] = [16, 17, 18, 19, 21, 22, 31, 82, 84, 85];

/// A position in the local frame: `north_m` (x), `east_m` (y), and `alt_m` **up** above home.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalPoint {
    /// Metres North of home (PX4 local x).
    pub north_m: f64,
    /// Metres East of home (PX4 local y).
    pub east_m: f64,
    /// Metres above home, positive up (PX4 local z is its negative).
    pub alt_m: f64,
}

/// One `SimpleItem` of the plan.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionItem {
    /// MAV_CMD id (22 takeoff, 16 waypoint, 21 land, 530 camera mode, ...).
    pub command: u16,
    /// MAV_FRAME id (3 = global, altitude relative to home).
    pub frame: u8,
    /// `params[0..7]`; `None` where the plan has `null`.
    pub params: [Option<f64>; 7],
    /// Whether the vehicle continues to the next item by itself.
    pub auto_continue: bool,
    /// Global position (lat, lon degrees; altitude as written), for positional commands.
    pub global: Option<GeoPoint>,
    /// Local position about the projection home, for positional commands.
    pub local: Option<LocalPoint>,
}

impl MissionItem {
    /// Whether PX4 flies to this item's position.
    pub fn is_positional(&self) -> bool {
        self.local.is_some()
    }
}

/// A mission: its items in order and the home its local positions are projected about.
#[derive(Debug, Clone, PartialEq)]
pub struct Mission {
    /// Every `SimpleItem`, including those without a position (kept, not flown).
    pub items: Vec<MissionItem>,
    /// `mission.plannedHomePosition` of the plan, if present.
    pub planned_home: Option<GeoPoint>,
    /// The projection reference of every [`MissionItem::local`].
    pub home: GeoPoint,
    /// Where the plan was read from.
    pub source: PathBuf,
}

impl Mission {
    /// Reads a `.plan`, projecting positions about `home` (the vehicle's home, where its local origin is).
    pub fn load(path: &Path, home: GeoPoint) -> Result<Self> {
        let text = read_text(path)?;
        Self::parse(&text, path, home)
    }

    /// Parses the text of a `.plan`; `path` only names the file in errors.
    pub fn parse(text: &str, path: &Path, home: GeoPoint) -> Result<Self> {
        let doc: Value = serde_json::from_str(text).map_err(|e| ModelError::Syntax {
            path: path.to_path_buf(),
            line: Some(e.line()),
            column: Some(e.column()),
            message: format!("not a QGroundControl plan (JSON): {e}"),
        })?;
        let err = |field: &str, msg: String| ModelError::field(path, field, msg);
        let mission = doc
            .get("mission")
            .ok_or_else(|| err("mission", "missing (is this a .plan file?)".into()))?;
        let items = mission
            .get("items")
            .and_then(Value::as_array)
            .ok_or_else(|| err("mission.items", "missing or not a list".into()))?;
        let planned_home = match mission.get("plannedHomePosition") {
            None | Some(Value::Null) => None,
            Some(v) => Some(parse_home(v).map_err(|m| err("mission.plannedHomePosition", m))?),
        };
        let projection = LocalProjection::new(home);
        let items = items
            .iter()
            .enumerate()
            .map(|(i, item)| parse_item(item, &projection).map_err(|(f, m)| err(&format!("mission.items[{i}]{f}"), m)))
            .collect::<Result<Vec<_>>>()?;
        let mission = Self {
            items,
            planned_home,
            home,
            source: path.to_path_buf(),
        };
        if mission.flight_path().is_empty() {
            return Err(err(
                "mission.items",
                "no item with a position (takeoff, waypoint or land)".into(),
            ));
        }
        Ok(mission)
    }

    /// A mission of plain waypoints (MAV_CMD_NAV_WAYPOINT, relative altitude) through local
    /// `(north_m, east_m)` points at `alt_m`, with global positions projected back about `home`.
    /// For synthetic missions in tests and experiments.
    pub fn through_local_points(points: &[(f64, f64)], alt_m: f64, home: GeoPoint) -> Self {
        let projection = LocalProjection::new(home);
        let items = points
            .iter()
            .map(|&(north_m, east_m)| {
                let (lat_deg, lon_deg) = projection.unproject(north_m, east_m);
                MissionItem {
                    command: CMD_WAYPOINT,
                    frame: 3,
                    params: [None, None, None, None, Some(lat_deg), Some(lon_deg), Some(alt_m)],
                    auto_continue: true,
                    global: Some(GeoPoint {
                        lat_deg,
                        lon_deg,
                        alt_m,
                    }),
                    local: Some(LocalPoint { north_m, east_m, alt_m }),
                }
            })
            .collect();
        Self {
            items,
            planned_home: None,
            home,
            source: PathBuf::from("synthetic"),
        }
    }

    /// The positions PX4 flies through, in order (takeoff, waypoints, land).
    pub fn flight_path(&self) -> Vec<LocalPoint> {
        self.items.iter().filter_map(|i| i.local).collect()
    }

    /// Cruise altitude: the highest altitude of the flight path, metres above home.
    pub fn cruise_altitude_m(&self) -> f64 {
        self.flight_path().iter().map(|p| p.alt_m).fold(0.0, f64::max)
    }
}

fn parse_home(v: &Value) -> std::result::Result<GeoPoint, String> {
    let nums: Vec<f64> = v
        .as_array()
        .ok_or_else(|| format!("expected [lat, lon, alt], got {v}"))?
        .iter()
        .map(|x| x.as_f64().ok_or_else(|| format!("expected numbers, got {x}")))
        .collect::<std::result::Result<_, _>>()?;
    match nums[..] {
        [lat, lon, alt] => check_geo(lat, lon).map(|_| GeoPoint {
            lat_deg: lat,
            lon_deg: lon,
            alt_m: alt,
        }),
        _ => Err(format!("expected [lat, lon, alt], got {v}")),
    }
}

fn check_geo(lat: f64, lon: f64) -> std::result::Result<(), String> {
    if !(-90.0..=90.0).contains(&lat) || !(-180.0..=180.0).contains(&lon) {
        return Err(format!("latitude {lat} / longitude {lon} out of range"));
    }
    Ok(())
}

type ItemError = (String, String);

fn parse_item(item: &Value, projection: &LocalProjection) -> std::result::Result<MissionItem, ItemError> {
    let kind = item.get("type").and_then(Value::as_str).unwrap_or("SimpleItem");
    if kind != "SimpleItem" {
        return Err((
            ".type".into(),
            format!("{kind:?} items are not supported; only SimpleItem"),
        ));
    }
    let command = match item.get("command").and_then(Value::as_u64) {
        Some(c) if c <= u64::from(u16::MAX) && mavlink::dialects::common::MavCmd::from_u64(c).is_some() => c as u16,
        _ => {
            let got = item.get("command").map_or("nothing".into(), Value::to_string);
            return Err((".command".into(), format!("{got} is not a known MAV_CMD id")));
        }
    };
    let frame = match item.get("frame").and_then(Value::as_u64) {
        Some(f) if f <= 21 => f as u8,
        other => return Err((".frame".into(), format!("{other:?} is not a MAV_FRAME id"))),
    };
    let params = parse_params(item)?;
    let auto_continue = item.get("autoContinue").and_then(Value::as_bool).unwrap_or(true);
    let (global, local) = if POSITIONAL.contains(&command) {
        let (global, local) = parse_position(frame, &params, projection)?;
        (Some(global), Some(local))
    } else {
        (None, None)
    };
    Ok(MissionItem {
        command,
        frame,
        params,
        auto_continue,
        global,
        local,
    })
}

/// The item's seven `params`, each a number or null.
fn parse_params(item: &Value) -> std::result::Result<[Option<f64>; 7], ItemError> {
    let raw = item
        .get("params")
        .and_then(Value::as_array)
        .ok_or_else(|| (".params".into(), "missing or not a list".into()))?;
    if raw.len() != 7 {
        return Err((".params".into(), format!("expected 7 entries, got {}", raw.len())));
    }
    let mut params = [None; 7];
    for (k, v) in raw.iter().enumerate() {
        params[k] = match v {
            Value::Null => None,
            v => Some(
                v.as_f64()
                    .ok_or_else(|| (format!(".params[{k}]"), format!("expected a number or null, got {v}")))?,
            ),
        };
    }
    Ok(params)
}

/// A positional item's place: as written (latitude, longitude in degrees, the altitude in metres of its
/// `frame`) and projected to local North/East metres with the altitude above home.
fn parse_position(
    frame: u8,
    params: &[Option<f64>; 7],
    projection: &LocalProjection,
) -> std::result::Result<(GeoPoint, LocalPoint), ItemError> {
    let (lat, lon, alt) = match (params[4], params[5], params[6]) {
        (Some(a), Some(b), Some(c)) => (a, b, c),
        _ => {
            return Err((
                ".params".into(),
                "a positional command needs lat, lon and altitude in params[4..7]".into(),
            ));
        }
    };
    check_geo(lat, lon).map_err(|m| (".params".to_string(), m))?;
    let home_alt = projection.reference().alt_m;
    let alt_rel = match frame {
        3 | 6 => alt,            // GLOBAL_RELATIVE_ALT(_INT): relative to home
        0 | 5 => alt - home_alt, // GLOBAL(_INT): AMSL
        f => {
            return Err((
                ".frame".into(),
                format!("frame {f} is not a global frame PX4 accepts for a position (use 3)"),
            ));
        }
    };
    let (n, e) = projection.project(lat, lon);
    let global = GeoPoint {
        lat_deg: lat,
        lon_deg: lon,
        alt_m: alt,
    };
    let local = LocalPoint {
        north_m: n,
        east_m: e,
        alt_m: alt_rel,
    };
    Ok((global, local))
}
