//! Mesh → perturbation field (a base quadric plus local cubed-quadric bumps), and that field
//! resampled into a coefficient volume so every command that reads a `.pgv` file works on it.
//! The algorithm and its choices are in `docs/perturbation.md`.

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;
use pgvol_core::Mesh;
use pgvol_field::Basis;
use pgvol_format::{PgvFile, PgvHeader};
use pgvol_perturb::{
    self as perturb, Cleanup, PerturbOptions, PerturbReport, PerturbationField, Strays,
};
use pgvol_sdf::sampling::Extent;
use pgvol_sdf::SignMode;

use crate::band::BAND_KEY;
use crate::decode::{decode, DecodeOptions};
use crate::distance::{mesh_sdf, sample};
use crate::emptiness::{require_mesh_surface, Sides};
use crate::encode::ENCODE_BAND;
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
    /// The pass that clears wrong nodes of the check grid away from the surface.
    pub cleanup: Cleanup,
    /// The passes that remove the stray pieces left on the check grid.
    pub strays: Strays,
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

/// Converts `mesh` into a perturbation field by the paper's iterative loop, checked on the
/// default resampling grid ([`CHECK_RES`]). Cancelling through `progress` stops the loop and
/// returns the cancellation error.
pub fn perturb(
    mesh: &Mesh,
    options: &PerturbOptions,
    progress: &dyn Progress,
) -> Result<Perturbed> {
    perturb_on(mesh, options, GridSpec::Res(CHECK_RES), progress)
}

/// [`perturb`], with the field checked on the grid `spec` gives for `mesh`: the grid the
/// output is contoured or resampled on (the list's header records it). After the loop, every
/// node of that grid farther than [`CHECK_MARGIN`] spacings from the mesh is put on the mesh's
/// side, then every stray piece the grid's node signs would contour is removed, so the
/// contoured field has the pieces of the mesh's own signed distance on that grid.
pub fn perturb_on(
    mesh: &Mesh,
    options: &PerturbOptions,
    spec: GridSpec,
    progress: &dyn Progress,
) -> Result<Perturbed> {
    crate::frame::require_near(mesh.offset, "the perturbation field")?;
    validate(options)?;
    let grid = spec.grid_for(mesh)?;
    // The mesh's distances, the field's resampled nodes and two label arrays per node.
    crate::memory::check_grid("checking the field's sides", &grid, 24)?;
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
    let truth = mesh_distances(mesh, &grid, progress)?;
    let (field, cleanup) =
        perturb::clear_points(&field, &check_points(&grid, &truth)).map_err(cannot_clear)?;
    let (field, strays, sides) = clear_strays(field, &grid, &truth, progress)?;
    require_mesh_surface(sides, "the perturbation field", mesh, grid.spacing)?;
    Ok(Perturbed {
        field,
        report,
        cleanup,
        strays,
    })
}

fn cannot_clear(e: perturb::PerturbationError) -> Error {
    Error::new(
        ErrorKind::InputFile,
        format!("cannot clear the field's stray pieces: {e}"),
    )
}

/// Nodes per axis of the default check grid: the default resampling grid, so the pieces the
/// default output would contour are checked.
pub const CHECK_RES: usize = crate::grid::DEFAULT_RES;

/// Check nodes nearer the surface than this many of their spacings are left to the stray
/// pass: a clearing ball there would be smaller than the grid resolves.
pub const CHECK_MARGIN: f32 = 0.5;

/// Most stray passes: one removes every piece it finds (each bump turns its own node only),
/// a second confirms; more would mean the bumps interfere.
pub const STRAY_ROUNDS: usize = 4;

/// The mesh's signed distance at every node of `grid` (exact within the encode band, its clamp
/// beyond: never more than the true distance, so a clearing ball stays clear of the surface).
fn mesh_distances(
    mesh: &Mesh,
    grid: &pgvol_core::Grid,
    progress: &dyn Progress,
) -> Result<Vec<f32>> {
    let sdf = mesh_sdf(mesh, SignMode::Auto)?;
    Ok(sample(&sdf, grid, Extent::Band(ENCODE_BAND), progress)?.values)
}

fn node_point(grid: &pgvol_core::Grid, i: usize) -> Vec3 {
    let [nx, ny, _] = grid.dims;
    grid.point(i % nx, (i / nx) % ny, i / (nx * ny))
}

/// The nodes of `grid` farther than [`CHECK_MARGIN`] spacings from the mesh, with their
/// signed distance `truth`.
fn check_points(grid: &pgvol_core::Grid, truth: &[f32]) -> Vec<(Vec3, f32)> {
    let margin = CHECK_MARGIN * grid.spacing;
    truth
        .iter()
        .enumerate()
        .filter(|(_, d)| d.abs() > margin)
        .map(|(i, &d)| (node_point(grid, i), d))
        .collect()
}

/// Removes the stray pieces of `field` on `grid`: its node signs, as [`resample_onto`] samples
/// them, labelled against the mesh's (`truth`), and every node of a stray region turned over
/// by a bump; repeated until none is left or [`STRAY_ROUNDS`] passes have run. Also gives the
/// sides of the last samples, the nodes the output is contoured from.
fn clear_strays(
    mut field: PerturbationField,
    grid: &pgvol_core::Grid,
    truth: &[f32],
    progress: &dyn Progress,
) -> Result<(PerturbationField, Strays, Sides)> {
    let mut total = Strays::default();
    let mut sides = Sides::default();
    for round in 0..=STRAY_ROUNDS {
        progress::check(progress)?;
        let samples = perturb::sample_band(&field, grid, RESAMPLE_BAND, &|_| {}).to_dense();
        let (nodes, pieces) =
            perturb::stray_nodes(grid.dims, &|i| samples[i] < 0.0, &|i| truth[i] < 0.0);
        if nodes.is_empty() || round == STRAY_ROUNDS {
            total.pieces_left = pieces;
            sides = Sides::of_values(&samples);
            break;
        }
        let points: Vec<(Vec3, f32)> = nodes
            .iter()
            .map(|&i| (node_point(grid, i), truth[i]))
            .collect();
        let (turned, pass) = perturb::clear_strays(&field, &points, grid.spacing as f64, pieces)
            .map_err(cannot_clear)?;
        field = turned;
        total.pieces += pass.pieces;
        total.nodes += pass.nodes;
        total.against_mesh += pass.against_mesh;
        total.rounds += 1;
    }
    Ok((field, total, sides))
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

/// How a resampled perturbation field is stored: bit-exact binary32 coefficients, so the file
/// decodes to the node signs the stray pass checked. With the default fixed-point storage a
/// node of fandisk at 96³ turned over in the file, a one-node piece the field in memory did not
/// have. The price is bytes: binary32 files came out 3 to 4× larger in the runs measured (the
/// cow at 96³: 900 KB against 250 KB).
pub fn resampled_storage() -> crate::encode::StorageOptions {
    crate::encode::StorageOptions {
        precision: Some(pgvol_format::Precision::F32),
        ..Default::default()
    }
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
        sharp: None,
    })
}

/// Writes `field`'s function list with `header` (from [`perturbation_header`]) to `path`
/// atomically.
pub fn write_perturbation(
    path: impl AsRef<Path>,
    header: &PgvHeader,
    field: &PerturbationField,
) -> Result<()> {
    let path = path.as_ref();
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
        pgvol_field::fit::interp_sparse(
            grid,
            Basis::Bspline3,
            &samples,
            pgvol_core::progress::QUIET,
        )
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
