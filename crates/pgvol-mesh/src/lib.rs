//! Triangle meshes for pgvol: the [`Mesh`] type, readers and writers for OBJ, glTF/GLB, STL and
//! PLY, a reader for 3MF, cleaning (welding, degenerate removal) and topology statistics.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]
#![forbid(unsafe_code)]

mod chunks;
mod clean;
mod error;
mod format;
mod gltf_io;
mod io;
mod normals;
mod obj;
mod ply;
pub mod shapes;
mod stl;
mod threemf;
mod validate;

pub use clean::{clean, read_bytes_clean, read_clean, read_clean_in, CleanReport};
pub use error::MeshError;
pub use format::MeshFormat;
pub use io::{check_precision, read, read_bytes, read_ply_points, write, write_to};
pub use normals::{face_normal, output_normals, vertex_normals};
pub use pgvol_core::{write_atomic, FileError, Mesh, MeshStats};
pub use threemf::{DeclaredUnit, LengthUnit, UnitChoice};
pub use validate::{
    coordinate_out_of_range, f32_rounding_loss, mesh_problem, too_small, MAX_COORDINATE,
    MAX_F32_ROUNDING, MIN_EXTENT,
};
