//! Errors for reading and validating the competition's files, quoting the file and the field.

use std::path::PathBuf;

/// Anything wrong with an input file: unreadable, not parseable, or a field of the wrong kind.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The file could not be read or written.
    #[error("{path}: {action}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What was attempted ("cannot read", "cannot write").
        action: &'static str,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not well-formed (YAML, JSON or CSV syntax).
    #[error("{path}{}: {message}", location_suffix(*.line, *.column))]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line, where the parser knows it.
        line: Option<usize>,
        /// 1-based column, where the parser knows it.
        column: Option<usize>,
        /// What the parser said.
        message: String,
    },
    /// A field is missing, of the wrong type, or holds a value the format does not allow.
    #[error("{path}: {field}: {message}")]
    Field {
        /// The file.
        path: PathBuf,
        /// The field's path, e.g. `simulation.obstacles[1].size.l`.
        field: String,
        /// What is wrong, quoting the value.
        message: String,
    },
}

fn location_suffix(line: Option<usize>, column: Option<usize>) -> String {
    match (line, column) {
        (Some(l), Some(c)) => format!(":{l}:{c}"),
        (Some(l), None) => format!(":{l}"),
        _ => String::new(),
    }
}

impl ModelError {
    /// A field error.
    pub fn field(path: impl Into<PathBuf>, field: impl Into<String>, message: impl Into<String>) -> Self {
        Self::Field {
            path: path.into(),
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Result of reading a model file.
pub type Result<T> = std::result::Result<T, ModelError>;
