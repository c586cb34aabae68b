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
//! ```
//! use pgvol::{DecodeOptions, EncodeOptions, GridSpec, Silent, StorageOptions};
//!
//! # fn main() -> pgvol::Result<()> {
//! let dir = tempfile::tempdir().unwrap();
//! // A mesh file: here a unit sphere written by pgvol itself.
//! let sphere_path = dir.path().join("sphere.obj");
//! pgvol::write_mesh(&sphere_path, &pgvol::mesh::shapes::octasphere(4))?;
//!
//! // Load it (bit-identical vertices welded, degenerate triangles dropped).
//! let (mesh, _cleaned) = pgvol::read_mesh(&sphere_path)?;
//!
//! // Encode: signed distance on a 48³ grid, cubic B-spline coefficients.
//! let options = EncodeOptions { grid: GridSpec::Res(48), ..EncodeOptions::default() };
//! let encoded = pgvol::encode(&mesh, &options, &Silent)?;
//!
//! // Write it as a sparse, compressed .pgv file and read it back.
//! let pgv_path = dir.path().join("sphere.pgv");
//! pgvol::write_pgv(&pgv_path, &encoded.file, &StorageOptions::default())?;
//! let file = pgvol::read_pgv(&pgv_path)?;
//!
//! // Near the surface the field is the signed distance: -0.1 just inside the unit sphere.
//! // (Beyond the band of 4 grid spacings it holds a clamped value of the right sign.)
//! let (value, gradient) = file.volume.eval(glam::Vec3::new(0.9, 0.0, 0.0));
//! assert!((value + 0.1).abs() < 0.01);
//! assert!(gradient.x > 0.95);
//!
//! // Decode: contour the zero level set into a watertight mesh.
//! let surface = pgvol::decode(&file.volume, &DecodeOptions::default(), &Silent)?;
//! assert!(surface.stats().watertight);
//!
//! // Slice into layers 0.1 apart along z.
//! let shape = pgvol::Shape::from_file(file);
//! let layers = pgvol::slice(&shape, &pgvol::SliceSettings::new(0.1), &Silent)?;
//! assert!(layers.len() >= 19);
//!
//! // Grow the shape by 0.05: the field shifts, the surface moves out.
//! let grown = pgvol::offset(&shape, 0.05)?;
//! assert!((grown.eval(glam::Vec3::new(0.9, 0.0, 0.0)).0 + 0.15).abs() < 0.01);
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]
#![forbid(unsafe_code)]
#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]

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
mod exact_field;
mod export;
mod frame;
pub use frame::require_near;
mod grid;
mod lattice;
mod memory;
mod mesh_io;
mod operand;
mod perturb;
mod pgv_io;
mod pieces;
mod points;
mod points_warnings;
mod progress;
mod remesh;
mod repair;
mod resolution;
mod shape;
mod slice;

pub use blend::{blend, BlendOperator, BlendSettings, Blended, IPatchWeights, DEFAULT_LAMBDA};
pub use csg::{
    covering_grid, csg, csg_name, edited_file, load_operands, operand_fields, CsgSettings,
    ResultUse, CSG_RES,
};
pub use decode::{decode, decode_shape, DecodeOptions, SPECK_VOXELS};
pub use decode_file::decode_file;
pub use distance::{
    mesh_sdf, signed_distance, write_grid, GridFormat, MeshDistance, SdfGrid, SdfOptions,
};
pub use encode::{
    check_output, check_pgv_name, encode, is_pgv, pgv_bytes, read_coefficients_nrrd, write_pgv,
    write_pgv_to, EncodeOptions, Encoded, StorageOptions, StorageReport, BAND_KEY, ENCODE_BAND,
    MIN_BAND, PG_ORDER, PG_RADIUS,
};
pub use error::{Error, ErrorKind, Remedy, Result};
pub use eval::{
    eval, eval_csv, point_json, read_points, read_points_file, sample, Evaluation, ReportPoint,
};
pub use exact_field::{MeshField, NODE_BAND};
pub use export::{export, ExportKind, THREEMF_UNIT, THREEMF_UNITS};
pub use grid::{GridSpec, DEFAULT_RES, MAX_RES, MIN_RES};
pub use lattice::{
    infill, lattice, lattice_reach, make_lattice, solid_report, SolidReport,
    BYTES_PER_LATTICE_BRICK,
};
pub use memory::{human, memory_limit, parse_size, set_memory_limit};
pub use mesh_io::{
    check_mesh_output, mesh_format, mesh_from_parts, mesh_from_world, read_mesh, read_mesh_bytes,
    write_mesh, write_mesh_to,
};
pub use operand::{parse_operand, LoadedOperand, Operand, OperandField, Primary, PRIMARY_FORMS};
pub use perturb::{
    perturb, perturb_on, perturbation_header, perturbation_mesh, resample, resample_onto,
    resampled_storage, write_perturbation, Perturbed, CHECK_MARGIN, CHECK_RES, RESAMPLE_BAND,
    SOURCE_KEY, STRAY_ROUNDS,
};
pub use pgv_io::{
    pgv_info, read_field_source, read_field_source_bytes, read_pgv, read_pgv_bytes, read_pgv_from,
    recorded_band, FieldSource,
};
pub use pgvol_perturb::{
    Cleanup, PerturbOptions, PerturbReport, PerturbationField, StopReason, Strays, DESCENT_STEPS,
};
pub use points::{
    contours, points, points_bytes, points_with_sections, read_cloud_text, read_layers,
    read_point_cloud, PointsMethod, PointsOptions, Reconstructed, SectionSettings, Sections,
    MAX_CUBIC_CENTRES, POINT_TEXT_EXTENSIONS,
};
pub use progress::{Progress, Silent};
pub use remesh::{remesh, RemeshField, RemeshOptions, Remeshed};
pub use repair::{parse_face, parse_mask, repair, repair_reach, DEFAULT_ALPHA, DEFAULT_COARSE};
pub use resolution::{check_pieces, check_wall, EXTRA_PIECES, MIN_WALL_SPACINGS, PIECES_FACTOR};
pub use shape::{
    check_offset, check_thickness, exact_reach, growth, offset, operation_name, operation_shift,
    parse_drain, shell, Shape, ShellKind, SHAPE_RES, SLICE_RES,
};
pub use slice::{
    layer_frame, slice, slice_file, write_layers, LayerFormat, SliceSettings, Sliced,
    DEFAULT_UNITS_MM,
};

/// The stage crates, for what the facade does not wrap.
pub use pgvol_contour as contour;
pub use pgvol_core as core;
pub use pgvol_field as field;
pub use pgvol_format as format;
pub use pgvol_mesh as mesh;
pub use pgvol_metrics as metrics;
pub use pgvol_ops as ops;
pub use pgvol_perturb as perturbation;
pub use pgvol_points as point_cloud;
pub use pgvol_sdf as sdf;
pub use pgvol_slice as slicing;

pub use glam;
pub use pgvol_contour::Method;
pub use pgvol_core::{Grid, Mesh};
pub use pgvol_field::{Basis, CoefficientVolume, FitMethod, FitReport};
pub use pgvol_format::{PgvFile, PgvHeader, Precision};
pub use pgvol_metrics::Comparison;
pub use pgvol_ops::{
    Blend, BoolOp, Continuity, Drain, Face, Grade, Lattice, LatticeSolid, LatticeStyle, Mask,
    MaskReport, Ramp, Restore, ShellSide, Tpms, MAX_CONTINUITY, TPMS_NAMES,
};
pub use pgvol_points::{PointCloud, PointsReport};
pub use pgvol_sdf::SignMode;
pub use pgvol_slice::{Axis, Layer, LayerFrame};

/// Seconds spent per stage of a call.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Timings {
    /// Reading the input.
    pub read: f64,
    /// Signed distances.
    pub sdf: f64,
    /// Fitting the coefficients.
    pub fit: f64,
    /// Contouring.
    pub contour: f64,
    /// Writing the output.
    pub write: f64,
}

/// Area-uniform samples drawn on each mesh by [`compare`] unless told otherwise.
pub const COMPARE_SAMPLES: usize = 200_000;

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
