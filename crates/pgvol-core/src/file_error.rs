//! The error of every file reader and writer: which file, and what is wrong with it.

use std::fmt;
use std::path::{Path, PathBuf};

/// A failure to read, write or interpret a file.
///
/// `problem` is a plain sentence meant for a person, e.g. "face 12 refers to vertex 9001 but the
/// file has 400 vertices"; `Display` prefixes it with the path so callers can print it as is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileError {
    pub path: PathBuf,
    pub problem: String,
}

impl FileError {
    pub fn new(path: impl AsRef<Path>, problem: impl Into<String>) -> Self {
        Self {
            path: path.as_ref().to_path_buf(),
            problem: problem.into(),
        }
    }
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.problem)
    }
}

impl std::error::Error for FileError {}
