//! Mesh → signed distance → coefficient volume → `.pgv` file, with the band it is exact in
//! recorded in the file.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use pgvol_core::Mesh;
use pgvol_field::{Basis, ClosestFn, CoefficientVolume, FitMethod, FitOptions, FitReport};
use pgvol_format::{PgvFile, Precision};
use pgvol_sdf::sampling::Extent;
use pgvol_sdf::SignMode;

use crate::band::BAND_KEY;
use crate::distance::{mesh_sdf, sample, sample_sparse, MeshDistance};
use crate::emptiness::{is_flat, require_mesh_surface, Sides, FLAT_MESH};
use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::exact_distance::ExactDistance;
use crate::grid::GridSpec;
use crate::memory::{check_grid, BYTES_PER_NODE};
use crate::progress::{self, Progress};
use crate::sharp::store::{attach_with, SharpOptions, SharpReport};
use crate::timings::Timings;

/// Exact distances within this many grid spacings of the surface when encoding: the cubic
/// B-spline near the surface depends on samples up to 2 nodes away directly and on farther ones
/// through the prefilter, whose influence falls by 0.268 per node.
pub const ENCODE_BAND: f32 = 4.0;

/// The narrowest band accepted: the cubic B-spline's support reaches two spacings.
pub const MIN_BAND: f32 = 2.0;

/// Pseudo-Gaussian continuity order when only the basis is chosen.
pub const PG_ORDER: u8 = 3;

/// Pseudo-Gaussian support radius, in grid spacings, when only the basis is chosen.
pub const PG_RADIUS: f32 = 1.5;

/// How a mesh becomes a coefficient volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncodeOptions {
    /// The grid (default 128 nodes per axis).
    pub grid: GridSpec,
    /// The basis (default the cubic B-spline, the most accurate per byte).
    pub basis: Basis,
    /// How the coefficients are found (default `Interp`, the exact prefilter).
    pub fit: FitMethod,
    /// Exact distances within this many grid spacings of the surface (default
    /// [`ENCODE_BAND`]); wider bands let offsets and shells reach farther from the file.
    pub band: f32,
    /// How inside is told from outside (default automatic).
    pub sign: SignMode,
    /// Whether the exact vertices of the cells at creases and corners are stored, so that dual
    /// contouring of the file keeps them sharp (default not: see [`SharpOptions`]).
    pub sharp: SharpOptions,
}

impl Default for EncodeOptions {
    fn default() -> Self {
        Self {
            grid: GridSpec::default(),
            basis: Basis::Bspline3,
            fit: FitMethod::Interp,
            band: ENCODE_BAND,
            sign: SignMode::Auto,
            sharp: SharpOptions::default(),
        }
    }
}

impl EncodeOptions {
    /// Refuses contradictory or out-of-range options.
    pub fn validate(&self) -> Result<()> {
        self.basis
            .validate()
            .map_err(|e| Error::parameter(format!("basis: {e}")))?;
        if !(self.band.is_finite() && self.band >= MIN_BAND) {
            return Err(Error::parameter(format!(
                "the band must be at least {MIN_BAND} grid spacings, got {}",
                self.band
            )));
        }
        self.sharp.validate()?;
        if let FitMethod::Iso { z_step: Some(z) } = self.fit {
            let max = pgvol_field::MAX_Z_STEP;
            if !(z.is_finite() && z > 0.0 && z <= max) {
                return Err(Error::parameter(format!(
                    "the isosurface step must be in (0, {max}] grid spacings, got {z}: the \
                     iso fit needs an isosurface within half a spacing of every node"
                )));
            }
        }
        Ok(())
    }
}

/// A fitted file ready to write, with how the fit went.
#[derive(Clone, Debug)]
pub struct Encoded {
    /// Header and coefficients.
    pub file: PgvFile,
    /// The fit's solver report.
    pub fit: FitReport,
    /// What the sharp-feature section holds.
    pub sharp: SharpReport,
    /// Seconds per stage.
    pub timings: Timings,
}

/// Encodes `mesh` by `options` into a `.pgv` file in memory.
pub fn encode(mesh: &Mesh, options: &EncodeOptions, progress: &dyn Progress) -> Result<Encoded> {
    options.validate()?;
    let grid = options.grid.grid_for(mesh)?;
    // Known empty before any distance is sampled (which for an open sheet on a fine grid costs
    // minutes of winding numbers).
    if is_flat(mesh) {
        return Err(Error::new(
            ErrorKind::EmptyResult,
            format!("the encoded field would be empty: {FLAT_MESH}"),
        ));
    }
    match options.fit {
        FitMethod::Interp => {
            let creases = crate::memory::crease_bytes(mesh, options.sharp.enabled);
            crate::memory::check_sparse_encode_then("encoding", mesh, &grid, options.band, creases)?
        }
        _ => check_grid("encoding", &grid, BYTES_PER_NODE)?,
    }
    let mut timings = Timings::default();
    let start = Instant::now();
    // Built once: the sharp-feature stage queries the same distance. Without it, the fit
    // lets the distance queries go once it has its samples.
    let exact = ExactDistance::new(mesh, options.sign)?;
    let timed = (&mut timings, start);
    let (fitted, exact) = fit_exact(exact, options.sharp.enabled, grid, options, timed, progress)?;
    if let Some(message) = unconverged(&fitted.report) {
        progress.warn(&message);
    }
    let sides = Sides::of_volume(&fitted.volume);
    require_mesh_surface(sides, "the encoded field", mesh, grid.spacing)?;
    let mut file = encoded_file(mesh, fitted.volume, &fitted.report, fitted.band);
    let start = Instant::now();
    let sign = options.sign;
    let sharp = attach_with(
        &mut file,
        mesh,
        sign,
        exact.as_ref(),
        &options.sharp,
        progress,
    )?;
    timings.sharp = start.elapsed().as_secs_f64();
    Ok(Encoded {
        file,
        fit: fitted.report,
        sharp,
        timings,
    })
}

/// What to say of a fit whose solver stopped at its iteration cap, `None` when it converged.
fn unconverged(report: &FitReport) -> Option<String> {
    (!report.converged).then(|| {
        format!(
            "the {} fit's {} solver stopped at its iteration cap without converging ({} \
             iterations, relative residual {:.1e}), so the field may miss the surface; the \
             interp fit of the B-spline bases solves no system, and a coarser grid converges in \
             fewer iterations",
            report.method, report.solver, report.iterations, report.residual
        )
    })
}

/// The header of `volume`, fitted as `fit` reports (to `mesh` when there is one), with the fit's
/// residual and solver.
pub(crate) fn fitted_header(
    volume: &CoefficientVolume,
    fit: &FitReport,
    mesh: Option<&Mesh>,
) -> pgvol_format::PgvHeader {
    let mut header = pgvol_format::header_for(volume, fit.method.as_str(), mesh);
    header
        .metadata
        .insert("fit_residual".into(), format!("{:e}", fit.residual));
    header
        .metadata
        .insert("fit_solver".into(), fit.solver.clone());
    header
}

/// A coefficient fit that failed, as the facade's error.
pub(crate) fn fit_failed(e: impl std::error::Error + Send + Sync + 'static) -> Error {
    Error::new(
        ErrorKind::Internal,
        format!("cannot fit the coefficients: {e}"),
    )
    .caused_by(e)
}

/// The file of `volume` fitted to `mesh`: its header records the fit and the band (in grid
/// spacings) within which the samples were exact distances.
pub(crate) fn encoded_file(
    mesh: &Mesh,
    volume: CoefficientVolume,
    fit: &FitReport,
    band: Option<f32>,
) -> PgvFile {
    let header = encoded_header(mesh, &volume, fit, band);
    PgvFile { header, volume }
}

/// The header of [`encoded_file`].
pub(crate) fn encoded_header(
    mesh: &Mesh,
    volume: &CoefficientVolume,
    fit: &FitReport,
    band: Option<f32>,
) -> pgvol_format::PgvHeader {
    let mut header = fitted_header(volume, fit, Some(mesh));
    if let Some(band) = band {
        header
            .metadata
            .insert(BAND_KEY.into(), format!("{}", band * volume.grid.spacing));
    }
    header
}

/// A fitted volume, its report and the band of exact node distances it was fitted to.
pub(crate) struct Fitted {
    pub volume: CoefficientVolume,
    pub report: FitReport,
    /// Grid spacings from the surface within which the node samples were exact distances;
    /// `None` when the fit queried the mesh's distance wherever it needed it.
    pub band: Option<f32>,
}

/// The coefficient volume of `mesh` on `grid`. `Interp` interpolates band-limited node
/// distances; `Wls` adds the mesh's closest points to the same samples; `Iso` queries the
/// mesh's distance wherever its collocation points move.
pub(crate) fn fit_volume(
    mesh: &Mesh,
    grid: pgvol_core::Grid,
    options: &EncodeOptions,
    timings: &mut Timings,
    progress: &dyn Progress,
) -> Result<Fitted> {
    let start = Instant::now();
    let sdf = mesh_sdf(mesh, options.sign)?;
    fit_volume_with(
        Distances::Owned(Box::new(sdf)),
        grid,
        options,
        (timings, start),
        progress,
    )
}

/// [`fit_volume_with`] of the distance of `exact`, handed back when `keep` asks (for a later
/// stage querying the same distance), else dropped once the fit needs no more of it.
pub(crate) fn fit_exact<'m>(
    exact: ExactDistance<'m>,
    keep: bool,
    grid: pgvol_core::Grid,
    options: &EncodeOptions,
    timings: (&mut Timings, Instant),
    progress: &dyn Progress,
) -> Result<(Fitted, Option<ExactDistance<'m>>)> {
    if keep {
        let fitted = fit_volume_with(
            Distances::Borrowed(exact.sdf()),
            grid,
            options,
            timings,
            progress,
        )?;
        return Ok((fitted, Some(exact)));
    }
    let distances = Distances::Owned(Box::new(exact.into_sdf()));
    let fitted = fit_volume_with(distances, grid, options, timings, progress)?;
    Ok((fitted, None))
}

/// A mesh's distance queries handed to [`fit_volume_with`]: borrowed from a caller that queries
/// them again afterwards, or owned, to be dropped as soon as the fit needs no more of them
/// (an interpolating fit once its samples are taken, which leaves the fit the memory of the
/// hierarchy and the winding-number tree).
enum Distances<'a> {
    Borrowed(&'a pgvol_sdf::MeshSdf),
    Owned(Box<pgvol_sdf::MeshSdf>),
}

impl Distances<'_> {
    fn sdf(&self) -> &pgvol_sdf::MeshSdf {
        match self {
            Distances::Borrowed(sdf) => sdf,
            Distances::Owned(sdf) => sdf,
        }
    }
}

/// [`fit_volume`] with the mesh's distance queries `sdf` built, since `start` (the distance
/// stage's time counts from there).
fn fit_volume_with(
    distances: Distances,
    grid: pgvol_core::Grid,
    options: &EncodeOptions,
    (timings, start): (&mut Timings, Instant),
    progress: &dyn Progress,
) -> Result<Fitted> {
    let fit_options = FitOptions::default();
    let mut band = None;
    let fitted = match options.fit {
        FitMethod::Interp => {
            // Sparse from end to end: band bricks sampled, fitted locally, far bricks a side.
            band = Some(options.band);
            let sampled = sample_sparse(distances.sdf(), &grid, options.band, progress)?;
            timings.sdf = start.elapsed().as_secs_f64();
            drop(distances);
            pgvol_core::heap::return_freed_pages();
            // Handed over, so the fit drops the samples behind it.
            let samples = sampled.values;
            progress::stage(progress, "fit", |update| {
                pgvol_field::fit::interp_sparse_owned(grid, options.basis, samples, update)
            })?
        }
        FitMethod::Wls => {
            let sdf = distances.sdf();
            let width = options.band.max(fit_options.band);
            band = Some(width);
            let extent = Extent::Band(width);
            let sampled = sample(sdf, &grid, extent, progress)?;
            timings.sdf = start.elapsed().as_secs_f64();
            // Closest points need no sign, so they skip the winding number.
            let surface = ClosestFn(|p: Vec3, reach: f32| {
                sdf.bvh().closest(p, reach * reach).map(|c| c.point)
            });
            progress::stage(progress, "fit", |update| {
                let values = &sampled.values;
                let basis = options.basis;
                pgvol_field::wls_band(grid, basis, values, &surface, &fit_options, update)
            })?
        }
        FitMethod::Iso { .. } => {
            let sdf = distances.sdf();
            timings.sdf = start.elapsed().as_secs_f64();
            progress::stage(progress, "fit", |update| {
                pgvol_field::fit(
                    grid,
                    options.basis,
                    options.fit,
                    &MeshDistance(sdf),
                    &fit_options,
                    update,
                )
            })?
        }
    };
    let (volume, report) = fitted.map_err(fit_failed)?;
    timings.fit = report.seconds;
    Ok(Fitted {
        volume,
        report,
        band,
    })
}

/// How a `.pgv` file stores its coefficients.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StorageOptions {
    /// Coefficient precision; `None` (the default) picks the smallest that keeps the stored
    /// coefficients within 1 % of the grid spacing, which is `Fixed` for distance fields.
    pub precision: Option<Precision>,
    /// Every coefficient as f32 instead of the sparse compressed bricks around the surface.
    pub dense: bool,
}

/// What writing a file stored, `None` parts for dense files.
pub type StorageReport = Option<pgvol_format::EncodeReport>;

/// A `.pgv` file's bytes and what they store.
#[derive(Clone, Debug)]
pub struct PgvBytes {
    /// The whole file.
    pub bytes: Vec<u8>,
    /// The stored bricks and their sizes; `None` for a dense file.
    pub storage: StorageReport,
}

/// The bytes of `file` as `storage` asks. Sparse files keep the bricks around nodes within the
/// recorded band less one spacing, dilated by the basis support: that covers every cell of a
/// level set the band supports without storing the clamped nodes at the band's edge.
pub fn pgv_bytes(file: &PgvFile, storage: &StorageOptions) -> Result<PgvBytes> {
    let (encoded, report) = encoded_pgv(file, storage)?;
    Ok(PgvBytes {
        bytes: encoded.to_bytes(),
        storage: report,
    })
}

/// A file encoded as `storage` asks, held in pieces: a sparse file's blobs are written as they
/// are rather than copied into one buffer (at 4096³ that buffer and its frame were 0.7 GB).
enum EncodedPgv<'a> {
    Dense(&'a PgvFile),
    Sparse(Box<pgvol_format::SparsePgv>),
}

impl EncodedPgv<'_> {
    fn to_bytes(&self) -> Vec<u8> {
        match self {
            EncodedPgv::Dense(file) => pgvol_format::encode_pgv(file),
            EncodedPgv::Sparse(s) => s.to_bytes(),
        }
    }

    fn write_to(&self, w: &mut dyn Write) -> std::io::Result<()> {
        match self {
            EncodedPgv::Dense(file) => w.write_all(&pgvol_format::encode_pgv(file)),
            EncodedPgv::Sparse(s) => s.write_to(w),
        }
    }
}

fn encoded_pgv<'a>(
    file: &'a PgvFile,
    storage: &StorageOptions,
) -> Result<(EncodedPgv<'a>, StorageReport)> {
    if storage.dense {
        return Ok((EncodedPgv::Dense(file), None));
    }
    let options = sparse_options(&file.header, storage);
    let (encoded, report) = pgvol_format::sparse_pgv(file, &options).writing()?;
    Ok((EncodedPgv::Sparse(Box::new(encoded)), Some(report)))
}

/// The sparse storage options of a file of `header`: its recorded band, less one spacing,
/// decides the stored bricks.
pub(crate) fn sparse_options(
    header: &pgvol_format::PgvHeader,
    storage: &StorageOptions,
) -> pgvol_format::EncodeOptions {
    let mut options = pgvol_format::EncodeOptions {
        precision: storage.precision,
        ..Default::default()
    };
    if let Some(band) = crate::band::header_band(header) {
        options.band = band / header.grid.spacing - 1.0;
    }
    options
}

/// Writes `file` to `path` atomically; see [`pgv_bytes`].
pub fn write_pgv(
    path: impl AsRef<Path>,
    file: &PgvFile,
    storage: &StorageOptions,
) -> Result<StorageReport> {
    let path = path.as_ref();
    let (encoded, report) = encoded_pgv(file, storage).map_err(|e| e.at(path))?;
    pgvol_core::write_atomic(path, |w| encoded.write_to(w)).writing()?;
    Ok(report)
}

/// Writes `file` to any writer; see [`pgv_bytes`].
pub fn write_pgv_to(
    w: &mut dyn Write,
    file: &PgvFile,
    storage: &StorageOptions,
) -> Result<StorageReport> {
    let (encoded, report) = encoded_pgv(file, storage)?;
    encoded.write_to(w).map_err(|e| {
        Error::new(ErrorKind::OutputFile, format!("write failed: {e}")).caused_by(e)
    })?;
    Ok(report)
}

/// A coefficient NRRD written by [`export`](crate::export()) back as a file. Its storage
/// should stay dense unless a precision is asked for, so the coefficients copy bit for bit:
/// see [`StorageOptions::for_copy`].
pub fn read_coefficients_nrrd(path: impl AsRef<Path>) -> Result<PgvFile> {
    let path = path.as_ref();
    pgvol_format::nrrd::read_coefficients_nrrd(path).reading()
}

impl StorageOptions {
    /// Storage for coefficients copied from elsewhere: dense (bit-exact) unless `precision`
    /// asks for quantised sparse bricks.
    pub fn for_copy(precision: Option<Precision>) -> Self {
        Self {
            precision,
            dense: precision.is_none(),
        }
    }
}

/// Whether `path` names a `.pgv` file.
pub fn is_pgv(path: impl AsRef<Path>) -> bool {
    let path = path.as_ref();
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("pgv"))
}

/// Refuses an output name that is not `.pgv`.
pub fn check_pgv_name(path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    if is_pgv(path) {
        Ok(())
    } else {
        Err(Error::new(ErrorKind::OutputFile, "expected a .pgv file name").at(path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unconverged_fit_is_said_with_its_figures_and_a_converged_one_is_not() {
        let mut report = FitReport {
            method: "wls".into(),
            solver: "cgls".into(),
            iterations: 500,
            residual: 3e-3,
            converged: true,
            seconds: 1.0,
            spurious_sign_changes: 0,
            z_step: None,
            initial_residual: None,
            normal_residual: None,
            unknowns: 1000,
            rows: 2000,
            stages: Default::default(),
        };
        assert_eq!(unconverged(&report), None);
        report.converged = false;
        let message = unconverged(&report).expect("a warning");
        assert!(
            message.contains("wls") && message.contains("500 iterations"),
            "{message}"
        );
        assert!(
            message.contains("3.0e-3") && !message.contains("--"),
            "{message}"
        );
    }
}
