//! The error of the readers and writers.

use pgvol_core::FileError;

/// The error of every reader and writer here: the file and what is wrong with it.
pub type MeshError = FileError;
