//! Typed access to fields of a parsed YAML document, with errors that name the field path.

use serde_json::{Map, Value};

/// What is wrong with one field, before the file name is attached.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FieldError {
    pub field: String,
    pub message: String,
}

pub(crate) type FieldResult<T> = std::result::Result<T, FieldError>;

pub(crate) fn fail<T>(field: &str, message: impl Into<String>) -> FieldResult<T> {
    Err(FieldError {
        field: field.to_string(),
        message: message.into(),
    })
}

pub(crate) fn join(parent: &str, key: &str) -> String {
    if parent.is_empty() {
        key.to_string()
    } else {
        format!("{parent}.{key}")
    }
}

/// Describes a value for an error message, e.g. `"abc" (a string)`.
pub(crate) fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null (also what .nan and .inf read as)".into(),
        Value::Bool(b) => format!("{b} (a boolean)"),
        Value::Number(n) => format!("{n}"),
        Value::String(s) => format!("{s:?} (a string)"),
        Value::Array(_) => "a list".into(),
        Value::Object(_) => "a mapping".into(),
    }
}

pub(crate) fn as_map<'a>(v: &'a Value, field: &str) -> FieldResult<&'a Map<String, Value>> {
    v.as_object()
        .map_or_else(|| fail(field, format!("expected a mapping, got {}", describe(v))), Ok)
}

/// A finite number; YAML strings holding numbers are refused, as a typo there would change a test.
pub(crate) fn number(v: &Value, field: &str) -> FieldResult<f64> {
    match v.as_f64() {
        Some(x) if x.is_finite() => Ok(x),
        _ => fail(field, format!("expected a finite number, got {}", describe(v))),
    }
}

pub(crate) fn req_number(map: &Map<String, Value>, parent: &str, key: &str) -> FieldResult<f64> {
    let field = join(parent, key);
    map.get(key)
        .map_or_else(|| fail(&field, "missing"), |v| number(v, &field))
}

pub(crate) fn opt_number(map: &Map<String, Value>, parent: &str, key: &str) -> FieldResult<Option<f64>> {
    map.get(key).map(|v| number(v, &join(parent, key))).transpose()
}

pub(crate) fn opt_string(map: &Map<String, Value>, parent: &str, key: &str) -> FieldResult<Option<String>> {
    match map.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(Value::String(s)) => Ok(Some(s.trim().to_string())),
        // Aerialist accepts `port: 14541`; keep scalars as their text.
        Some(v @ (Value::Number(_) | Value::Bool(_))) => Ok(Some(v.to_string())),
        Some(v) => fail(&join(parent, key), format!("expected text, got {}", describe(v))),
    }
}

/// Refuses keys outside `allowed`, so a misspelt key is reported instead of silently ignored.
pub(crate) fn known_keys(map: &Map<String, Value>, parent: &str, allowed: &[&str]) -> FieldResult<()> {
    for key in map.keys() {
        if !allowed.contains(&key.as_str()) {
            return fail(
                &join(parent, key),
                format!("unknown key (expected one of: {})", allowed.join(", ")),
            );
        }
    }
    Ok(())
}
