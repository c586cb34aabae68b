//! The library's errors as the Python exceptions of `pgvol._errors`, which carry the kind and
//! the path.

use pyo3::prelude::*;
use pyo3::types::PyAnyMethods;

/// The module holding the exception classes.
const ERRORS: &str = "pgvol._errors";

/// The exception class named `name`, or the error of importing it.
fn class<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import(ERRORS)?.getattr(name)
}

/// An exception of class `name` with the message, the kind's name and the path.
fn raise(py: Python<'_>, name: &str, message: &str, kind: &str, path: Option<String>) -> PyErr {
    match class(py, name).and_then(|c| c.call1((message, kind, path))) {
        Ok(value) => PyErr::from_value(value),
        Err(e) => e,
    }
}

/// A library error as its exception class: input and output files, bad parameters and empty
/// results (`ValueError`s), resource limits (a `MemoryError`), cancellation and internal
/// failures. An
/// input file that does not exist is also a `FileNotFoundError`.
pub(crate) fn to_py(py: Python<'_>, e: pgvol::Error) -> PyErr {
    use pgvol::ErrorKind as K;
    let path = e
        .path()
        .filter(|p| !p.as_os_str().is_empty())
        .map(|p| p.to_path_buf());
    let name = match e.kind() {
        K::InputFile if path.as_ref().is_some_and(|p| !p.exists()) => "MissingFileError",
        K::InputFile => "InputFileError",
        K::OutputFile => "OutputFileError",
        // A grid too coarse is a parameter to change: the resolution.
        K::BadParameter | K::Unresolved => "ParameterError",
        K::ResourceLimit => "ResourceLimitError",
        K::EmptyResult => "EmptyResultError",
        K::Cancelled => "CancelledError",
        K::Internal => "InternalError",
    };
    let path = path.map(|p| p.to_string_lossy().into_owned());
    raise(py, name, e.message(), e.kind().name(), path)
}

/// A bad argument found by the bindings themselves (a dtype, a shape, a name): a
/// `ParameterError`, which is a `ValueError`.
pub(crate) fn parameter(py: Python<'_>, message: impl AsRef<str>) -> PyErr {
    raise(
        py,
        "ParameterError",
        message.as_ref(),
        pgvol::ErrorKind::BadParameter.name(),
        None,
    )
}

/// The warning category of the library's warnings.
pub(crate) fn warning_class(py: Python<'_>) -> PyResult<Bound<'_, PyAny>> {
    class(py, "PgvolWarning")
}
