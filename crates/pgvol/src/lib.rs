//! pgvol turns triangle meshes into compact, smooth implicit fields and back into meshes.
//!
//! A **coefficient volume** stores one coefficient per grid node of a compactly supported
//! basis; the field is their weighted sum, smooth, O(1) per evaluation, with exact analytic
//! gradients. This crate is the product's API: the command-line tool, the tests and the
//! bindings all call it, and it re-exports the stage crates underneath.
//!
//! Conventions: signed distance is negative inside and positive outside, in the mesh's units;
//! the grid is a cube of side 1.1 × the mesh's longest extent, centred on it, with N nodes per
//! axis, x varying fastest in flat arrays.
//!
//! # A tour
//!
//! Every job goes through one value, [`Field`]: made from a mesh or read from a `.pgv` file,
//! changed by operations that each return a new `Field`, and queried, contoured, sliced or
//! saved. The modules hold the readers and writers ([`io`]), the limits and defaults
//! ([`limits`]) and the less common jobs.
//!
//! ```
//! use pgvol::{DecodeOptions, EncodeOptions, Field, GridSpec, Silent, SliceOptions, StorageOptions};
//!
//! # fn main() -> pgvol::Result<()> {
//! let dir = tempfile::tempdir().unwrap();
//! // A mesh file: here a unit sphere written by pgvol itself, read back (bit-identical
//! // vertices welded, degenerate triangles dropped).
//! let sphere_path = dir.path().join("sphere.obj");
//! pgvol::io::write_mesh(&sphere_path, &pgvol::mesh::shapes::octasphere(4))?;
//! let mesh = pgvol::io::read_mesh(&sphere_path)?.mesh;
//!
//! // Encode: signed distance on a 48³ grid, cubic B-spline coefficients, distances kept 8 grid
//! // spacings out so that the operations below read exact distances.
//! let options = EncodeOptions { grid: GridSpec::Res(48), band: 8.0, ..EncodeOptions::default() };
//! let field = Field::from_mesh(&mesh, &options, &Silent)?;
//!
//! // Save it as a sparse, compressed .pgv file and load it again.
//! let pgv_path = dir.path().join("sphere.pgv");
//! field.save(&pgv_path, &StorageOptions::default())?;
//! let field = Field::load(&pgv_path)?;
//!
//! // Near the surface the field is the signed distance: -0.05 just inside the unit sphere,
//! // with a unit gradient pointing out. Farther than the band of exact distances (the 8 spacings
//! // less the basis support's 2, here 0.28) it holds a value of the right sign, and `exact`
//! // says which is which.
//! let at = field.eval(&[glam::DVec3::new(0.95, 0.0, 0.0), glam::DVec3::new(0.5, 0.0, 0.0)]);
//! assert!((at[0].value + 0.05).abs() < 0.005 && at[0].gradient[0] > 0.95 && at[0].exact);
//! assert!(at[1].value < 0.0 && !at[1].exact);
//!
//! // Contour the zero level set into a watertight mesh.
//! let surface = field.to_mesh(&DecodeOptions::default(), &Silent)?;
//! assert!(surface.stats().watertight);
//!
//! // Slice into layers 0.1 apart along z: 20 layers from -0.95 to 0.95, each a disc whose
//! // area is that of the sphere's section, π(1 - z²).
//! let sliced = field.slice(&SliceOptions::new(0.1), &Silent)?;
//! assert_eq!(sliced.layers.len(), 20);
//! for layer in &sliced.layers {
//!     let z = f64::from(layer.height);
//!     let disc = std::f64::consts::PI * (1.0 - z * z);
//!     assert!((layer.area() - disc).abs() < 0.03 * disc + 0.01, "{z}: {}", layer.area());
//! }
//!
//! // Operations chain: grow by 0.05, then hollow to walls of 0.2; the surface moves out,
//! // and the centre is now outside the solid.
//! let part = field.offset(0.05)?.hollow(0.2, &[], &Silent)?;
//! let [outer, centre] = [glam::DVec3::new(1.04, 0.0, 0.0), glam::DVec3::ZERO];
//! let values = part.eval(&[outer, centre]);
//! assert!(values[0].value < 0.0 && values[1].value > 0.0);
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]

mod band;
mod blend;
mod csg;
mod decode;
mod decode_file;
mod distance;
pub mod distributed;
mod emptiness;
mod encode;
mod error;
mod eval;
mod exact_distance;
mod exact_field;
mod export;
mod field_value;
mod frame;
mod grid;
mod lattice;
mod lattice_3mf;
mod memory;
mod mesh_io;
mod operand;
mod perturb;
mod perturb_field;
mod pgv_io;
mod pieces;
mod points;
mod points_warnings;
mod progress;
mod remesh;
mod repair;
mod resample;
mod resolution;
pub mod sharp;
mod slice;
mod timings;
mod vdb_export;
mod vdb_in;
pub mod view;

pub use csg::{CsgOptions, ResultUse};
pub use decode::DecodeOptions;
pub use distance::SdfOptions;
pub use encode::{encode, EncodeOptions, Encoded, StorageOptions, StorageReport};
pub use error::{Error, ErrorKind, Remedy, Result};
pub use eval::Evaluation;
pub use export::{ExportKind, ExportOptions};
pub use field_value::{Field, OpenOptions, ShellKind, ShellOptions};
pub use grid::GridSpec;
pub use lattice::{Latticed, SolidReport};
pub use operand::{Operand, Primary};
pub use points::{PointsOptions, Reconstructed};
pub use progress::{Progress, Silent};
pub use remesh::{remesh, RemeshField, RemeshOptions, Remeshed};
pub use repair::Repaired;
pub use resample::ResampleOptions;
pub use slice::{SliceOptions, Sliced};
pub use timings::Timings;

pub use glam;
pub use pgvol_contour::Method;
pub use pgvol_core::{Grid, Mesh};
pub use pgvol_field::{Basis, CoefficientVolume, FitMethod};
pub use pgvol_format::{PgvFile, PgvHeader, Precision};
pub use pgvol_metrics::Comparison;
pub use pgvol_ops::{Blend, BoolOp, Lattice};
pub use pgvol_sdf::SignMode;
pub use pgvol_slice::{Axis, Layer};

/// Reading and writing files: meshes, `.pgv` files, point clouds and point lists, layer files,
/// sampled grids and the formats other tools read.
pub mod io {
    pub use crate::band::recorded_band;
    pub use crate::distance::{write_grid, GridFormat};
    pub use crate::encode::{
        check_pgv_name, is_pgv, pgv_bytes, read_coefficients_nrrd, write_pgv, write_pgv_to,
        PgvBytes,
    };
    pub use crate::eval::{read_points, read_points_file};
    pub use crate::export::{export, VdbCompression};
    pub use crate::mesh_io::{
        check_mesh_output, mesh_format, mesh_from_parts, mesh_from_world, read_mesh,
        read_mesh_bytes, read_mesh_in, write_mesh, write_mesh_to, ReadMesh,
    };
    pub use crate::pgv_io::{
        pgv_info, read_field_source, read_field_source_bytes, read_pgv, read_pgv_bytes,
        read_pgv_from, FieldSource,
    };
    pub use crate::points::{
        read_cloud_text, read_layers, read_point_cloud, POINT_TEXT_EXTENSIONS,
    };
    pub use crate::slice::{write_layers, LayerFormat};
    pub use crate::vdb_in::{encode_vdb, is_vdb, VdbEncodeOptions};
    pub use pgvol_mesh::output_normals;
}

/// Work on a `.pgv` file window by window, so memory follows the surface rather than the grid.
pub mod stream {
    pub use crate::decode_file::decode_file;
    pub use crate::slice::slice_file;
}

/// Defaults, limits and the memory cap every job is estimated against before it starts.
pub mod limits {
    pub use crate::band::BAND_KEY;
    pub use crate::blend::DEFAULT_LAMBDA;
    pub use crate::csg::CSG_RES;
    pub use crate::decode::SPECK_VOXELS;
    pub use crate::encode::{ENCODE_BAND, MIN_BAND, PG_ORDER, PG_RADIUS};
    pub use crate::exact_field::NODE_BAND;
    pub use crate::export::{THREEMF_UNIT, THREEMF_UNITS, VDB_BAND};
    pub use crate::field_value::{SHAPE_RES, SLICE_RES};
    pub use crate::grid::{DEFAULT_RES, MAX_RES, MIN_RES};
    pub use crate::lattice::BYTES_PER_LATTICE_BRICK;
    pub use crate::memory::{memory_limit, set_memory_limit};
    pub use crate::points::MAX_CUBIC_CENTRES;
    pub use crate::repair::{DEFAULT_ALPHA, DEFAULT_COARSE, MAX_ALPHA};
    pub use crate::resolution::{EXTRA_PIECES, MIN_WALL_SPACINGS, PIECES_FACTOR};
    pub use crate::slice::DEFAULT_UNITS_MM;
    pub use crate::vdb_export::{MAX_VDB_BAND, VDB_GRID_NAME};
    pub use pgvol_ops::{MAX_CONTINUITY, TPMS_NAMES};

    /// Area-uniform samples drawn on each mesh by [`crate::compare`] unless told otherwise.
    pub const COMPARE_SAMPLES: usize = 200_000;
}

/// Checks of parameters that callers can make before any heavy work.
pub mod checks {
    pub use crate::field_value::{check_offset, check_thickness, exact_reach};
    pub use crate::frame::require_near;
    pub use crate::lattice::lattice_reach;
    pub use crate::repair::repair_reach;
    pub use crate::resolution::{check_pieces, check_wall};
}

/// Signed distances of meshes: sampled on grids, or evaluated exactly anywhere.
pub mod distances {
    pub use crate::distance::{mesh_sdf, signed_distance, MeshDistance, SdfGrid};
    pub use crate::exact_field::MeshField;
}

/// Editing: Booleans and algebraic blends of operands, repairs inside masks, shells.
pub mod edit {
    pub use crate::blend::{blend, BlendOperator, BlendOptions, Blended, IPatchWeights};
    pub use pgvol_ops::{Continuity, Drain, Face, Mask, MaskReport, Restore, ShellSide};
}

/// Lattices for additive manufacturing: triply periodic surfaces cut to a part or filling it.
pub mod lattices {
    pub use crate::lattice::make_lattice;
    pub use crate::lattice_3mf::{lattice_function, ImplicitPackage, LatticeCut};
    pub use pgvol_ops::{Grade, LatticeSolid, LatticeStyle, Ramp, Tpms};
}

/// Surfaces from point clouds and from stacks of planar contours.
pub mod reconstruct {
    pub use crate::points::{
        contours, points, points_bytes, points_with_sections, PointsMethod, SectionOptions,
        Sections,
    };
    pub use pgvol_points::{PointCloud, PointsReport};
    pub use pgvol_slice::LayerFrame;
}

/// The perturbation method: a mesh as a list of quadric perturbations, its files, and its
/// resampling onto a coefficient volume.
pub mod perturbation {
    pub use crate::perturb::{
        perturb, perturb_on, perturbation_header, perturbation_mesh, resample, resample_onto,
        resampled_storage, write_perturbation, Perturbed, CHECK_MARGIN, CHECK_RES, RESAMPLE_BAND,
        SOURCE_KEY, STRAY_ROUNDS,
    };
    pub use pgvol_perturb::{
        Cleanup, PerturbOptions, PerturbReport, PerturbationField, StopReason, Strays,
        DESCENT_STEPS,
    };
}

/// The stage crates, for what the facade does not wrap.
pub use pgvol_contour as contour;
pub use pgvol_core as core;
pub use pgvol_field as field;
pub use pgvol_format as format;
pub use pgvol_mesh as mesh;
pub use pgvol_metrics as metrics;
pub use pgvol_ops as ops;
pub use pgvol_points as point_cloud;
pub use pgvol_sdf as sdf;
pub use pgvol_slice as slicing;

/// Surface distances and statistics of mesh `a` against reference mesh `b`, from `samples`
/// area-uniform samples on each, reproducible from `seed`.
pub fn compare(a: &Mesh, b: &Mesh, samples: usize, seed: u64) -> Result<Comparison> {
    if samples == 0 {
        return Err(Error::parameter("the number of samples must be positive"));
    }
    memory::check_memory(
        &format!("comparing with {samples} samples per mesh"),
        (samples as u64).saturating_mul(memory::BYTES_PER_SAMPLE),
        "use fewer samples",
    )?;
    // Both meshes in one frame, taken from their f64 world positions: a far mesh compared
    // with its copy keeps the precision of its own size.
    let frame = if a.offset != glam::DVec3::ZERO {
        a.offset
    } else {
        b.offset
    };
    let (a, b) = (a.in_frame(frame), b.in_frame(frame));
    Ok(pgvol_metrics::compare(&a, &b, samples, seed)?)
}
