//! File formats for fields: pgvol's own `.pgv` coefficient files, NRRD and NPY grids for
//! exchange with other tools, and 3MF level-set packages.

mod brick_codec;
mod dense_alloc;
mod fixed_step;
pub mod grid_files;
pub mod nrrd;
pub mod pgv;
pub mod read_profile;
pub mod sparse;
mod sparse_read;
mod stored_band;
pub mod threemf;

pub use fixed_step::{FixedScale, FIXED_KNEE, FIXED_RATIO, FIXED_STEP, FREE_TOLERANCE};
pub use pgv::{
    decode_pgv, encode_pgv, header_for, read_pgv, write_pgv, FormatError, PgvFile, PgvHeader,
};
pub use sparse::{
    encode_pgv_with, pgv_info, read_brick, write_pgv_with, Brick, Compression, EncodeOptions,
    EncodeReport, PgvInfo, Precision, Predictor, SparseParams,
};
