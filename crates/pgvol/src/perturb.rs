//! Mesh → perturbation field (a base quadric plus local cubed-quadric bumps), and that field
//! resampled into a coefficient volume so every command that reads a `.pgv` file works on it.
//! The algorithm and its choices are in `docs/perturbation.md`.

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;
use pgvol_core::Mesh;
use pgvol_field::perturb::{self, Cleanup, PerturbOptions, PerturbReport, PerturbationField};
use pgvol_field::Basis;
use pgvol_format::{PgvFile, PgvHeader};
use pgvol_sdf::sampling::Extent;
use pgvol_sdf::SignMode;

use crate::decode::{decode, DecodeOptions};
use crate::distance::{mesh_sdf, sample};
use crate::encode::{BAND_KEY, ENCODE_BAND};
use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::grid::GridSpec;
use crate::progress::{self, Progress};

/// Header metadata key naming where a resampled file's field came from.
pub const SOURCE_KEY: &str = "source";

/// A mesh converted into a perturbation field, with the loop's report.
#[derive(Clone, Debug)]
pub struct Perturbed {
    /// The base quadric and its perturbations.
    pub field: PerturbationField,
    /// Functions, deviations before and after, the error after each step, why it stopped.
    pub report: PerturbReport,
    /// The pass that clears stray pieces on the check grid ([`CHECK_RES`]).
    pub cleanup: Cleanup,
}

/// Refuses options the loop cannot run with.
fn validate(options: &PerturbOptions) -> Result<()> {
    if options.max_functions == 0 {
        return Err(Error::parameter(
            "the number of functions must be at least 1",
        ));
    }
    if !(options.tolerance.is_finite() && options.tolerance >= 0.0) {
        return Err(Error::parameter(format!(
            "the tolerance must be a fraction of the diagonal of at least 0 (e.g. 0.001), got {}",
            options.tolerance
        )));
    }
    Ok(())
}

/// Converts `mesh` into a perturbation field by the paper's iterative loop. Cancelling through
/// `progress` stops the loop and returns the cancellation error.
pub fn perturb(
    mesh: &Mesh,
    options: &PerturbOptions,
    progress: &dyn Progress,
) -> Result<Perturbed> {
    crate::frame::require_near(mesh.offset, "the perturbation field")?;
    validate(options)?;
    let signs = sign_points(mesh, progress)?;
    progress::check(progress)?;
    progress.stage("perturb");
    let built = perturb::build(mesh, &signs, options, &mut |done| {
        progress.update(done);
        !progress.cancelled()
    });
    progress.finish();
    progress::check(progress)?;
    let (field, report) = built.map_err(|e| {
        Error::new(
            ErrorKind::InputFile,
            format!("cannot convert the mesh: {e}"),
        )
        .caused_by(e)
    })?;
    let checks = check_points(mesh, progress)?;
    let (field, cleanup) = perturb::clear_points(&field, &checks).map_err(|e| {
        Error::new(
            ErrorKind::InputFile,
            format!("cannot clear the field's stray pieces: {e}"),
        )
    })?;
    Ok(Perturbed {
        field,
        report,
        cleanup,
    })
}

/// Nodes per axis of the grid whose nodes are checked against the mesh's side after the loop:
/// the default resampling grid, so the pieces the default output would contour are checked.
pub const CHECK_RES: usize = crate::grid::DEFAULT_RES;

/// Check nodes nearer the surface than this many of their spacings are left out: a clearing
/// ball there would be smaller than the grid resolves.
pub const CHECK_MARGIN: f32 = 0.5;

/// The nodes of the [`CHECK_RES`]³ cube grid farther than [`CHECK_MARGIN`] spacings from the
/// mesh, with their signed distance (exact within the encode band, its clamp beyond: never
/// more than the true distance, so a clearing ball stays clear of the surface).
fn check_points(mesh: &Mesh, progress: &dyn Progress) -> Result<Vec<(Vec3, f32)>> {
    let grid = GridSpec::Res(CHECK_RES).grid_for(mesh)?;
    crate::memory::check_grid("checking the field's sides", &grid, 8)?;
    let sdf = mesh_sdf(mesh, SignMode::Auto)?;
    let sampled = sample(&sdf, &grid, Extent::Band(ENCODE_BAND), progress)?;
    let margin = CHECK_MARGIN * grid.spacing;
    let [nx, ny, _] = grid.dims;
    Ok(sampled
        .values
        .iter()
        .enumerate()
        .filter(|(_, d)| d.abs() > margin)
        .map(|(i, &d)| (grid.point(i % nx, (i / nx) % ny, i / (nx * ny)), d))
        .collect())
}

/// Nodes per axis of the coarse grid whose exact signed distances guard the sides (the
/// default cube around the mesh).
pub const SIGN_RES: usize = 64;

/// Sign points nearer the surface than this many coarse spacings are left out: the
/// perturbations near the surface are held by the probes along the vertex normals.
pub const SIGN_MARGIN: f32 = 1.5;

/// The nodes of a [`SIGN_RES`]³ grid farther than [`SIGN_MARGIN`] spacings from the mesh,
/// with their exact signed distance.
fn sign_points(mesh: &Mesh, progress: &dyn Progress) -> Result<Vec<(Vec3, f32)>> {
    let grid = GridSpec::Res(SIGN_RES).grid_for(mesh)?;
    let sdf = mesh_sdf(mesh, SignMode::Auto)?;
    let sampled = sample(&sdf, &grid, Extent::Dense, progress)?;
    let margin = SIGN_MARGIN * grid.spacing;
    let [nx, ny, _] = grid.dims;
    Ok(sampled
        .values
        .iter()
        .enumerate()
        .filter(|(_, d)| d.abs() > margin)
        .map(|(i, &d)| (grid.point(i % nx, (i / nx) % ny, i / (nx * ny)), d))
        .collect())
}

/// How far from the surface the resampled nodes hold the field's distance estimate, in grid
/// spacings: the encode band, so offsets and shells reach as far as on an encoded mesh.
pub const RESAMPLE_BAND: f32 = ENCODE_BAND;

/// The header of `field`'s function list (`perturbation-f64`): the grid `spec` gives for
/// `mesh` (where readers resample the field), the cubic B-spline basis they resample with, the
/// mesh's box and hash, and metadata `source = perturbation`, `perturbations` (the count) and
/// the resampling band.
pub fn perturbation_header(
    field: &PerturbationField,
    mesh: &Mesh,
    spec: GridSpec,
) -> Result<PgvHeader> {
    let grid = spec.grid_for(mesh)?;
    let bounds = mesh.bounds().map(|(lo, hi)| [lo.to_array(), hi.to_array()]);
    let mut metadata = BTreeMap::new();
    metadata.insert(BAND_KEY.into(), format!("{}", RESAMPLE_BAND * grid.spacing));
    metadata.insert(SOURCE_KEY.into(), "perturbation".into());
    metadata.insert("perturbations".into(), field.terms().len().to_string());
    Ok(PgvHeader {
        basis: Basis::Bspline3,
        fit: "perturbation".into(),
        grid,
        units: "source mesh units".into(),
        encoding: pgvol_format::ENCODING_PERTURBATION.into(),
        source_bounds: bounds,
        source_hash: Some(pgvol_format::pgv::mesh_hash(mesh)),
        metadata,
        sparse: None,
    })
}

/// Writes `field`'s function list with `header` (from [`perturbation_header`]) to `path`
/// atomically.
pub fn write_perturbation(
    path: &Path,
    header: &PgvHeader,
    field: &PerturbationField,
) -> Result<()> {
    crate::encode::check_pgv_name(path)?;
    pgvol_format::write_perturbation(path, header, field).writing()
}

/// The perturbation field as a cubic B-spline coefficient volume on the grid `spec` gives
/// for `mesh` (the mesh the field was built from: it fixes the box and the header's source).
/// See [`resample_onto`].
pub fn resample(
    field: &PerturbationField,
    mesh: &Mesh,
    spec: GridSpec,
    progress: &dyn Progress,
) -> Result<PgvFile> {
    let header = perturbation_header(field, mesh, spec)?;
    crate::memory::check_sparse_encode("resampling", mesh, &header.grid, RESAMPLE_BAND)?;
    resample_onto(field, &header, progress)
}

/// The perturbation field as a cubic B-spline coefficient volume on `header.grid`, with the
/// header's source and metadata (its encoding and fit those of the volume).
///
/// Nodes hold the first-order distance estimate `M / |∇M|` clamped to [`RESAMPLE_BAND`]
/// spacings. Only grid bricks the zero set may reach are sampled: a brick is sampled when its
/// corners and centre disagree in sign or one of them estimates the surface within the brick's
/// half-diagonal plus the band; every other brick takes the side of its centre.
pub fn resample_onto(
    field: &PerturbationField,
    header: &PgvHeader,
    progress: &dyn Progress,
) -> Result<PgvFile> {
    let grid = header.grid;
    let samples = progress::stage(progress, "sample", |update| {
        perturb::sample_band(field, &grid, RESAMPLE_BAND, update)
    })?;
    let (volume, _) = progress::stage(progress, "fit", |_| {
        pgvol_field::fit::interp_sparse(grid, Basis::Bspline3, &samples)
    })??;
    let mut out = pgvol_format::header_for(&volume, "interp", None);
    out.source_bounds = header.source_bounds;
    out.source_hash = header.source_hash.clone();
    out.metadata = header.metadata.clone();
    Ok(PgvFile {
        header: out,
        volume,
    })
}

/// The zero set of the resampled field as a mesh, every piece kept (so components can be
/// compared with the input's).
pub fn perturbation_mesh(file: &PgvFile, progress: &dyn Progress) -> Result<Mesh> {
    let options = DecodeOptions {
        min_component: Some(0.0),
        ..DecodeOptions::default()
    };
    decode(&file.volume, &options, progress)
}
