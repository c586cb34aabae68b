//! The error of every reader and writer of this crate.

use std::path::{Path, PathBuf};

/// Why a `.pgv` file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {problem}")]
pub struct FormatError {
    pub path: PathBuf,
    pub problem: String,
}

pub(crate) fn err(path: &Path, problem: impl Into<String>) -> FormatError {
    FormatError {
        path: path.to_path_buf(),
        problem: problem.into(),
    }
}
