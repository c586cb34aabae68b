//! File formats for fields: pgvol's own `.pgv` coefficient files, and NRRD and NPY grids for
//! exchange with other tools.

pub mod grid_files;
pub mod pgv;

pub use pgv::{read_pgv, write_pgv, FormatError, PgvFile, PgvHeader};
