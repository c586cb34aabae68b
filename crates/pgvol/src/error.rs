//! The one error type of the library: what kind of failure, which file, and what went wrong.

use std::fmt;
use std::path::{Path, PathBuf};

/// Broad classes of failure, for callers that map errors onto their own (exit codes, Python
/// exception classes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// An input file is missing, unreadable, malformed or describes something unusable.
    InputFile,
    /// An output file cannot be written, or its name asks for a format that does not exist.
    OutputFile,
    /// A parameter is out of range or contradicts another.
    BadParameter,
    /// The job would exceed a size limit (grid nodes, memory).
    ResourceLimit,
    /// The result would be empty: nothing inside, or inside everywhere with no surface.
    EmptyResult,
    /// The grid is too coarse for what was asked: a wall thinner than it resolves, or a result
    /// that breaks into far more pieces than its input. [`Error::resolution`] gives the grid
    /// that would work.
    Unresolved,
    /// The caller's [`Progress`](crate::Progress) asked to stop.
    Cancelled,
    /// A stage failed on valid input: a defect in the library.
    Internal,
}

impl ErrorKind {
    /// A short lower-case name, stable for scripts.
    pub fn name(self) -> &'static str {
        match self {
            ErrorKind::InputFile => "input file",
            ErrorKind::OutputFile => "output file",
            ErrorKind::BadParameter => "bad parameter",
            ErrorKind::ResourceLimit => "resource limit",
            ErrorKind::EmptyResult => "empty result",
            ErrorKind::Unresolved => "unresolved",
            ErrorKind::Cancelled => "cancelled",
            ErrorKind::Internal => "internal",
        }
    }
}

/// What a caller can change to make a refused call work. The message says it in the library's
/// terms; front ends with options of their own (the command line's flags) name them from this.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Remedy {
    /// Allow replacing the existing, read-only output file.
    Replace,
    /// Raise the memory limit ([`crate::set_memory_limit`]).
    MemoryLimit,
    /// Encode the mesh again with a band of at least this many grid spacings.
    Band(f32),
    /// A finer grid.
    FinerGrid,
    /// Give the box (two corners) the result should cover.
    CoveringBox,
}

/// A failure of a library call: its [`ErrorKind`], the file it concerns (if any), a sentence for
/// a person and the underlying error (if any). `Display` gives `path: message`.
#[derive(Debug)]
pub struct Error {
    kind: ErrorKind,
    path: Option<PathBuf>,
    message: String,
    resolution: Option<usize>,
    remedy: Option<Remedy>,
    source: Option<Box<dyn std::error::Error + Send + Sync + 'static>>,
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An error of `kind` with a message and no file.
    pub fn new(kind: ErrorKind, message: impl Into<String>) -> Self {
        Self {
            kind,
            path: None,
            message: message.into(),
            resolution: None,
            remedy: None,
            source: None,
        }
    }

    /// A bad parameter, named in the message.
    pub fn parameter(message: impl Into<String>) -> Self {
        Self::new(ErrorKind::BadParameter, message)
    }

    /// The same error about `path`.
    pub fn at(mut self, path: impl AsRef<Path>) -> Self {
        self.path = Some(path.as_ref().to_path_buf());
        self
    }

    /// The same error caused by `source`.
    pub fn caused_by(mut self, source: impl std::error::Error + Send + Sync + 'static) -> Self {
        self.source = Some(Box::new(source));
        self
    }

    /// The same error with the nodes per axis (over the same box) of a grid that would work.
    pub fn needing_resolution(mut self, nodes: usize) -> Self {
        self.resolution = Some(nodes);
        self
    }

    /// The same error with what would make the call work.
    pub fn with_remedy(mut self, remedy: Remedy) -> Self {
        self.remedy = Some(remedy);
        self
    }

    /// What would make the call work, when the library knows.
    pub fn remedy(&self) -> Option<Remedy> {
        self.remedy
    }

    /// Nodes per axis of a grid over the same box that would work, for an
    /// [`ErrorKind::Unresolved`] error.
    pub fn resolution(&self) -> Option<usize> {
        self.resolution
    }

    /// What kind of failure this is.
    pub fn kind(&self) -> ErrorKind {
        self.kind
    }

    /// The file the error concerns, if any.
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The sentence describing the problem, without the path.
    pub fn message(&self) -> &str {
        &self.message
    }

    /// A file error from a stage (`pgvol_core::FileError`, format errors) as `kind`.
    pub(crate) fn file(kind: ErrorKind, path: &Path, problem: impl Into<String>) -> Self {
        Self::new(kind, problem).at(path)
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.path {
            Some(p) if !p.as_os_str().is_empty() => write!(f, "{}: {}", p.display(), self.message),
            _ => f.write_str(&self.message),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.source
            .as_deref()
            .map(|e| e as &(dyn std::error::Error + 'static))
    }
}

/// Stage errors that name a file: their own path and problem, under the caller's `kind`.
pub(crate) trait FileFailure {
    /// The error as a library error of `kind`.
    fn into_error(self, kind: ErrorKind) -> Error;
}

impl FileFailure for pgvol_core::FileError {
    fn into_error(self, kind: ErrorKind) -> Error {
        Error::file(kind, &self.path, self.problem)
    }
}

impl FileFailure for pgvol_format::FormatError {
    fn into_error(self, kind: ErrorKind) -> Error {
        Error::file(kind, &self.path, self.problem)
    }
}

/// `Result` of a stage whose error names a file, mapped to the library's error of `kind`.
pub(crate) trait FileResult<T> {
    /// The failure as an input-file error.
    fn reading(self) -> Result<T>;
    /// The failure as an output-file error.
    fn writing(self) -> Result<T>;
}

impl<T, E: FileFailure> FileResult<T> for std::result::Result<T, E> {
    fn reading(self) -> Result<T> {
        self.map_err(|e| e.into_error(ErrorKind::InputFile))
    }
    fn writing(self) -> Result<T> {
        self.map_err(|e| e.into_error(ErrorKind::OutputFile))
    }
}

impl From<pgvol_core::GridError> for Error {
    fn from(e: pgvol_core::GridError) -> Self {
        let kind = match e {
            pgvol_core::GridError::TooManyNodes(..) => ErrorKind::ResourceLimit,
            _ => ErrorKind::BadParameter,
        };
        Error::new(kind, format!("cannot make the grid: {e}")).caused_by(e)
    }
}

impl From<pgvol_field::FieldError> for Error {
    fn from(e: pgvol_field::FieldError) -> Self {
        Error::new(ErrorKind::BadParameter, e.to_string()).caused_by(e)
    }
}

impl From<pgvol_ops::OpsError> for Error {
    fn from(e: pgvol_ops::OpsError) -> Self {
        Error::new(ErrorKind::BadParameter, e.to_string()).caused_by(e)
    }
}

impl From<pgvol_slice::SliceError> for Error {
    fn from(e: pgvol_slice::SliceError) -> Self {
        let kind = match e {
            pgvol_slice::SliceError::Stopped => ErrorKind::Cancelled,
            pgvol_slice::SliceError::BadParameter(_) => ErrorKind::BadParameter,
        };
        Error::new(kind, e.to_string()).caused_by(e)
    }
}

impl From<pgvol_sdf::SdfError> for Error {
    fn from(e: pgvol_sdf::SdfError) -> Self {
        Error::new(
            ErrorKind::InputFile,
            format!("cannot build the distance field: {e}"),
        )
        .caused_by(e)
    }
}

impl From<pgvol_metrics::CompareError> for Error {
    fn from(e: pgvol_metrics::CompareError) -> Self {
        Error::new(ErrorKind::BadParameter, e.to_string()).caused_by(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_names_the_file_first() {
        let e = Error::new(ErrorKind::InputFile, "empty file").at("a/b.obj");
        assert_eq!(e.to_string(), "a/b.obj: empty file");
        assert_eq!(e.kind(), ErrorKind::InputFile);
        assert_eq!(e.path(), Some(Path::new("a/b.obj")));
        assert_eq!(
            Error::parameter("the resolution must be positive").to_string(),
            "the resolution must be positive"
        );
    }

    #[test]
    fn too_many_nodes_is_a_resource_limit() {
        let e: Error = pgvol_core::GridError::TooManyNodes(1 << 40, 1 << 33).into();
        assert_eq!(e.kind(), ErrorKind::ResourceLimit);
        assert!(std::error::Error::source(&e).is_some());
    }
}
