//! Mesh → perturbation field (a base quadric plus local cubed-quadric bumps), and that field
//! resampled into a coefficient volume so every command that reads a `.pgv` file works on it.
//! The algorithm and its choices are in `docs/perturbation.md`.

use glam::Vec3;
use pgvol_core::Mesh;
use pgvol_field::perturb::{self, PerturbOptions, PerturbReport, PerturbationField};
use pgvol_field::Basis;
use pgvol_format::PgvFile;
use pgvol_sdf::sampling::Extent;
use pgvol_sdf::SignMode;

use crate::decode::{decode, DecodeOptions};
use crate::distance::{mesh_sdf, sample};
use crate::encode::{BAND_KEY, ENCODE_BAND};
use crate::error::{Error, ErrorKind, Result};
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
    Ok(Perturbed { field, report })
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

/// The perturbation field as a cubic B-spline coefficient volume on the grid `spec` gives
/// for `mesh` (the mesh the field was built from: it fixes the box and the header's source).
///
/// Nodes hold the first-order distance estimate `M / |∇M|` clamped to [`RESAMPLE_BAND`]
/// spacings. Only grid bricks the zero set may reach are sampled: a brick is sampled when its
/// corners and centre disagree in sign or one of them estimates the surface within the brick's
/// half-diagonal plus the band; every other brick takes the side of its centre.
pub fn resample(
    field: &PerturbationField,
    mesh: &Mesh,
    spec: GridSpec,
    progress: &dyn Progress,
) -> Result<PgvFile> {
    let grid = spec.grid_for(mesh)?;
    crate::memory::check_sparse_encode("resampling", mesh, &grid, RESAMPLE_BAND)?;
    let samples = progress::stage(progress, "sample", |update| {
        perturb::sample_band(field, &grid, RESAMPLE_BAND, update)
    })?;
    let (volume, _) = progress::stage(progress, "fit", |_| {
        pgvol_field::fit::interp_sparse(grid, Basis::Bspline3, &samples)
    })??;
    let mut header = pgvol_format::header_for(&volume, "interp", Some(mesh));
    header
        .metadata
        .insert(BAND_KEY.into(), format!("{}", RESAMPLE_BAND * grid.spacing));
    header
        .metadata
        .insert(SOURCE_KEY.into(), "perturbation".into());
    header
        .metadata
        .insert("perturbations".into(), field.terms().len().to_string());
    Ok(PgvFile { header, volume })
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
