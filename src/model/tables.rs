//! The case study's side files: PX4 parameters (`NAME, value`) and Aerialist commands (`timestamp,mode,x,y,z,r`).

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::error::{ModelError, Result};

/// A PX4 parameter to set before the flight.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Param {
    /// PX4 parameter name, e.g. `NAV_ACC_RAD`.
    pub name: String,
    /// Value (PX4 int parameters are written as whole numbers).
    pub value: f64,
}

impl Param {
    /// Sets `name` to `value` in `params`, replacing any earlier value of it (the last one set wins).
    pub fn set(params: &mut Vec<Param>, name: &str, value: f64) {
        params.retain(|p| p.name != name);
        params.push(Param {
            name: name.to_string(),
            value,
        });
    }

    /// Overrides (or adds) parameters from `NAME=VALUE,NAME=VALUE` (an experiment's command-line list);
    /// the error names the item that is not `NAME=number`.
    pub fn override_from_list(params: &mut Vec<Param>, list: &str) -> std::result::Result<(), String> {
        for kv in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (name, value) = kv.split_once('=').ok_or_else(|| format!("{kv:?} is not NAME=VALUE"))?;
            let value: f64 = value
                .trim()
                .parse()
                .map_err(|_| format!("{kv:?}: the value is not a number"))?;
            Param::set(params, name.trim(), value);
        }
        Ok(())
    }
}

/// One Aerialist command: at `timestamp_us` switch to `mode` (3 = Mission: arm and start the mission).
///
/// `x, y, z, r` are Aerialist's manual-setpoint fields (stick units, used only by `mode` 100).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Command {
    /// Microseconds after the start of the test.
    pub timestamp_us: f64,
    /// Aerialist `FlightMode` value (PX4 commander numbering; 3 = Mission, 10 Takeoff, 11 Land, 20 Arm, ...).
    pub mode: i64,
    /// Setpoint x.
    pub x: f64,
    /// Setpoint y.
    pub y: f64,
    /// Setpoint z.
    pub z: f64,
    /// Setpoint r.
    pub r: f64,
}

/// Aerialist's flight modes that a commands table may hold.
pub const KNOWN_MODES: [i64; 15] = [-1, 0, 1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12, 20, 21];

fn syntax(path: &Path, line: usize, message: String) -> ModelError {
    ModelError::Syntax {
        path: path.to_path_buf(),
        line: Some(line),
        column: None,
        message,
    }
}

fn parse_finite(text: &str) -> Option<f64> {
    text.trim().parse::<f64>().ok().filter(|v| v.is_finite())
}

/// Parses a params CSV: one `NAME, value` per line; blank lines and `#` comments are skipped.
pub fn parse_params_csv(text: &str, path: &Path) -> Result<Vec<Param>> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (name, value) = line
            .split_once(',')
            .ok_or_else(|| syntax(path, i + 1, format!("expected `NAME, value`, got {line:?}")))?;
        let name = name.trim();
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') || name.len() > 16 {
            return Err(syntax(
                path,
                i + 1,
                format!("{name:?} is not a PX4 parameter name (A-Z, 0-9, _; at most 16)"),
            ));
        }
        let value = parse_finite(value).ok_or_else(|| {
            syntax(
                path,
                i + 1,
                format!("{name}: {:?} is not a finite number", value.trim()),
            )
        })?;
        out.push(Param {
            name: name.to_string(),
            value,
        });
    }
    Ok(out)
}

/// Parses a commands CSV with the header `timestamp,mode,x,y,z,r`.
pub fn parse_commands_csv(text: &str, path: &Path) -> Result<Vec<Command>> {
    let mut lines = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty());
    let header: Vec<String> = match lines.next() {
        Some((_, h)) => h.split(',').map(|s| s.trim().to_ascii_lowercase()).collect(),
        None => {
            return Err(syntax(
                path,
                1,
                "empty commands file (expected the header timestamp,mode,x,y,z,r)".into(),
            ));
        }
    };
    if header != ["timestamp", "mode", "x", "y", "z", "r"] {
        return Err(syntax(
            path,
            1,
            format!("expected the header timestamp,mode,x,y,z,r, got {:?}", header.join(",")),
        ));
    }
    let mut out = Vec::new();
    for (i, line) in lines {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != 6 {
            return Err(syntax(path, i + 1, format!("expected 6 values, got {}", cells.len())));
        }
        let mut v = [0.0; 6];
        for (k, cell) in cells.iter().enumerate() {
            v[k] = parse_finite(cell).ok_or_else(|| {
                syntax(
                    path,
                    i + 1,
                    format!("{}: {:?} is not a finite number", header[k], cell.trim()),
                )
            })?;
        }
        let cmd = command_from(v).map_err(|m| syntax(path, i + 1, m))?;
        out.push(cmd);
    }
    Ok(out)
}

/// Builds a command from `[timestamp, mode, x, y, z, r]`, checking the mode.
pub(crate) fn command_from(v: [f64; 6]) -> std::result::Result<Command, String> {
    if v[1].fract() != 0.0 || !KNOWN_MODES.contains(&(v[1] as i64)) {
        return Err(format!(
            "mode {} is not an Aerialist flight mode ({KNOWN_MODES:?})",
            v[1]
        ));
    }
    if v[0] < 0.0 {
        return Err(format!("timestamp {} is negative", v[0]));
    }
    Ok(Command {
        timestamp_us: v[0],
        mode: v[1] as i64,
        x: v[2],
        y: v[3],
        z: v[4],
        r: v[5],
    })
}

#[cfg(test)]
mod tests {

    #[test]
    fn a_parameter_list_overrides_and_adds_and_names_a_bad_item() {
        let mut p = vec![Param {
            name: "MPC_XY_VEL_MAX".into(),
            value: 12.0,
        }];
        Param::override_from_list(&mut p, "MPC_XY_VEL_MAX=1.0, COM_OBS_AVOID=1").unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].name, "MPC_XY_VEL_MAX");
        assert_eq!(p[0].value, 1.0);
        assert!(Param::override_from_list(&mut p, "X").unwrap_err().contains("\"X\""));
        assert!(
            Param::override_from_list(&mut p, "X=fast")
                .unwrap_err()
                .contains("number")
        );
    }
    use super::*;

    #[test]
    fn case_study_params_and_commands() {
        let p = parse_params_csv(
            "NAV_ACC_RAD, 0.5\nMIS_YAW_ERR, 12.0\nSDLOG_PROFILE, 7",
            Path::new("p.csv"),
        )
        .unwrap();
        assert_eq!(p.len(), 3);
        assert_eq!(
            p[2],
            Param {
                name: "SDLOG_PROFILE".into(),
                value: 7.0
            }
        );
        let c = parse_commands_csv("timestamp,mode,x,y,z,r\n1,3,0,0,0.5,0", Path::new("c.csv")).unwrap();
        assert_eq!(
            c,
            vec![Command {
                timestamp_us: 1.0,
                mode: 3,
                x: 0.0,
                y: 0.0,
                z: 0.5,
                r: 0.0
            }]
        );
    }

    #[test]
    fn bad_rows_name_the_line() {
        let e = parse_params_csv("A, 1\nB 2", Path::new("p.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("p.csv:2"), "{e}");
        let e = parse_params_csv("A, nan", Path::new("p.csv")).unwrap_err().to_string();
        assert!(e.contains("finite"), "{e}");
        let e = parse_commands_csv("timestamp,mode,x,y,z,r\n1,99,0,0,0,0", Path::new("c.csv"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.csv:2") && e.contains("mode 99"), "{e}");
        assert!(parse_commands_csv("", Path::new("c.csv")).is_err());
    }
}
