//! File formats for fields: pgvol's own `.pgv` coefficient files, NRRD and NPY grids for
//! exchange with other tools, and 3MF level-set packages.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]

mod container;
mod dense_alloc;
mod error;
mod fixed_step;
pub mod grid_files;
mod header;
pub mod implicit;
pub mod nrrd;
pub mod perturbation;
pub mod pgv;
pub mod sharp;
pub mod sparse;
mod sparse_params;
pub mod threemf;
pub mod vdb;

pub use error::FormatError;
pub use fixed_step::{FixedScale, FIXED_KNEE, FIXED_RATIO, FIXED_STEP, FREE_TOLERANCE};
pub use header::{header_for, PgvFile, PgvHeader, ENCODING_PERTURBATION};
pub use perturbation::{
    decode_perturbation, encode_perturbation, is_perturbation, write_perturbation,
};
pub use pgv::{decode_pgv, encode_pgv, read_pgv, write_pgv};
pub use sparse::{
    encode_pgv_with, pgv_info, read_brick, sparse_pgv, write_pgv_with, Brick, CompactBrick,
    CompactSlab, Compression, EncodeOptions, EncodeReport, PgvInfo, Precision, Predictor,
    SlabBricks, SlabReader, SlabSource, SparseParams, SparsePgv, StreamError, StreamedPgv,
};
