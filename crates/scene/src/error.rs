//! Errors of the scene crate: each names where the problem is (file and line, or field) and how to fix it.

use std::path::PathBuf;

/// Something wrong with a scene or its input.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file's content is malformed at a given place.
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line (0 when unknown).
        line: usize,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// A value is out of range or inconsistent.
    #[error("{field}: {message}")]
    Invalid {
        /// What holds the value: file and line, material, parameter or field name.
        field: String,
        /// What is wrong and how to fix it.
        message: String,
    },
    /// An unknown builtin scene or parameter.
    #[error("{0}")]
    Unknown(String),
}
