//! Finding coefficients from a signed distance function, matrix-free: `interp` (collocation at
//! the nodes), `iso` (the paper's points moved onto isosurfaces of the SDF) and `wls` (weighted
//! least squares around the zero surface).

mod band_operator;
mod band_rows;
mod golden;
mod interp;
mod iso;
mod layer_blocks;
mod node_sdf;
mod node_values;
pub mod operator;
mod options;
mod report;
mod row_kernels;
mod row_window;
mod sign_check;
pub mod solve;
mod sparse_interp;
mod sparse_node_values;
mod vector;
mod weighted;
mod wls;

pub use crate::distance::{ClosestFn, ClosestPoint, SdfFn, SignedDistance, SurfaceOf};
pub use golden::golden_section;
pub use interp::{collocation_is_spd, lattice_symbol_min};
pub use iso::MAX_Z_STEP;
pub use node_values::node_values;
pub use options::{FitMethod, FitOptions};
pub use report::{FitReport, FitStages};
pub use sign_check::spurious_sign_changes;
pub use sparse_interp::SPARSE_GROUP;
pub use sparse_node_values::{
    box_node_values_into, brick_node_values, brick_node_values_into, node_values_sparse,
};
pub use wls::wls_band;

use std::time::Instant;

use pgvol_core::progress::{Report, Span};
use pgvol_core::{Grid, SparseGrid};

use crate::basis::Basis;
use crate::prefilter::{prefilter_volume_with, CUBIC_POLE, QUADRATIC_POLE};
use crate::volume::{check_inputs, CoefficientVolume, FieldError};
use node_sdf::NodeSdf;
use sparse_interp::{prefilter_and_check, Checked, SampleStore};

/// Fits a coefficient volume on `grid` to the signed distance `sdf`.
/// The fraction done goes to `report` (sampling the distance at the nodes takes
/// the first tenth).
pub fn fit(
    grid: Grid,
    basis: Basis,
    method: FitMethod,
    sdf: &dyn SignedDistance,
    options: &FitOptions,
    report: Report,
) -> Result<(CoefficientVolume, FitReport), FieldError> {
    let start = Instant::now();
    let span = Span::whole(report);
    let nodes = NodeSdf::sample(&grid, sdf);
    span.report(0.1);
    let span = Some(span.part(0.1, 1.0));
    check_inputs(&grid, basis, &nodes.distance)?;
    let (coeffs, mut report) = match method {
        FitMethod::Interp => interp::fit_nodes(&grid, basis, &nodes.distance, options),
        FitMethod::Iso { z_step } => iso::fit(&grid, basis, &nodes, sdf, z_step, options, span)?,
        FitMethod::Wls => {
            let surface = SurfaceOf(sdf);
            wls::fit(&grid, basis, &nodes.distance, &surface, options, span)
        }
    };
    let volume = CoefficientVolume::new(grid, basis, coeffs)?;
    report.spurious_sign_changes = spurious_sign_changes(&volume, &nodes.distance);
    report.method = method.name().to_string();
    report.seconds = start.elapsed().as_secs_f64();
    Ok((volume, report))
}

/// Interpolates node samples (x fastest) in `basis`, with the solver's report.
pub fn interp_samples(
    grid: Grid,
    basis: Basis,
    samples: &[f32],
    options: &FitOptions,
) -> Result<(CoefficientVolume, FitReport), FieldError> {
    let start = Instant::now();
    check_inputs(&grid, basis, samples)?;
    let (coeffs, mut report) = interp::fit_nodes(&grid, basis, samples, options);
    report.method = FitMethod::Interp.name().to_string();
    report.stages.warm_start = start.elapsed().as_secs_f64();
    let volume = CoefficientVolume::new(grid, basis, coeffs)?;
    let t = Instant::now();
    report.spurious_sign_changes = spurious_sign_changes(&volume, samples);
    report.stages.check = t.elapsed().as_secs_f64();
    report.seconds = start.elapsed().as_secs_f64();
    Ok((volume, report))
}

/// Interpolates samples held sparsely — exact values in the stored bricks, each absent brick
/// the background of its side — without visiting the grid node by node: B-spline coefficients
/// are computed only for the stored bricks and the bricks around them, each group of bricks
/// prefiltered in a local window (the window's truncation moves coefficients by at most one f32
/// ulp, less than the dense filter's own rounding), and every other brick keeps the samples'
/// background, which the prefilter maps to itself. The result has the samples' background and
/// sides, and does not depend on the thread count.
///
/// Trilinear coefficients are the samples. Pseudo-Gaussian collocation is a global solve whose
/// coefficients are not the background far out, so those bases take the dense path
/// ([`interp_samples`] with default options on `samples.to_dense()`), with its memory and time.
///
/// The report's sign check covers the nodes of the stored coefficient bricks.
///
/// Both loops report to `report` per group of bricks and poll it for a stop: a stopped fit
/// returns at once with an incomplete volume, which the caller who asked for the stop discards.
pub fn interp_sparse(
    grid: Grid,
    basis: Basis,
    samples: &SparseGrid,
    report: Report,
) -> Result<(CoefficientVolume, FitReport), FieldError> {
    interp_sparse_from(grid, basis, SampleStore::Borrowed(samples), report)
}

/// [`interp_sparse`] taking the samples, whose bricks it drops a layer at a time once the
/// filter and the sign check have passed them, so memory holds the coefficients and a few brick
/// layers of samples rather than both whole. The same volume and report.
pub fn interp_sparse_owned(
    grid: Grid,
    basis: Basis,
    samples: SparseGrid,
    report: Report,
) -> Result<(CoefficientVolume, FitReport), FieldError> {
    interp_sparse_from(grid, basis, SampleStore::Owned(samples), report)
}

fn interp_sparse_from(
    grid: Grid,
    basis: Basis,
    samples: SampleStore,
    report: Report,
) -> Result<(CoefficientVolume, FitReport), FieldError> {
    let start = Instant::now();
    crate::volume::check_sparse(&grid, basis, samples.grid())?;
    let span = Some(Span::whole(report));
    let ((coeffs, checked), mut fit_report) = match basis {
        // The coefficients are the samples: no sign can change.
        Basis::Trilinear => (
            (samples.into_grid(), Checked::default()),
            report::report("none", None),
        ),
        Basis::Bspline2 => (
            prefilter_and_check(samples, basis, QUADRATIC_POLE, grid.spacing, span),
            report::report("prefilter", None),
        ),
        Basis::Bspline3 => (
            prefilter_and_check(samples, basis, CUBIC_POLE, grid.spacing, span),
            report::report("prefilter", None),
        ),
        Basis::Pg { .. } => {
            let dense = samples.grid().to_dense();
            return interp_samples(grid, basis, &dense, &FitOptions::default());
        }
    };
    fit_report.method = FitMethod::Interp.name().to_string();
    fit_report.spurious_sign_changes = checked.changes;
    fit_report.stages.check = checked.seconds;
    fit_report.stages.warm_start = start.elapsed().as_secs_f64() - checked.seconds;
    let volume = CoefficientVolume::from_sparse(grid, basis, coeffs)?;
    fit_report.seconds = start.elapsed().as_secs_f64();
    Ok((volume, fit_report))
}

/// Coefficient bricks of one slab of a sparse interpolation, for fitting a grid in parts.
pub type LayerBricks = Vec<([usize; 3], Box<pgvol_core::sparse::BrickValues>)>;

/// The stored coefficient bricks [`interp_sparse`] gives for the groups (of [`SPARSE_GROUP`]³
/// grid bricks) whose y and z group indices lie in `gy` and `gz`, bit for bit and in its
/// order, from samples that hold the whole grid's bricks within [`sparse_reach`] grid bricks
/// of those groups (others may be absent). With the report `interp_sparse` gives, less its timings and sign check.
/// Unstored bricks take the samples' sides, as in `interp_sparse`. Pseudo-Gaussians have no
/// local fit and are refused. Groups are reported to `report` and polled for a stop as in
/// `interp_sparse`.
pub fn interp_sparse_groups(
    grid: Grid,
    basis: Basis,
    samples: &SparseGrid,
    gy: std::ops::Range<usize>,
    gz: std::ops::Range<usize>,
    report: Report,
) -> Result<(LayerBricks, FitReport), FieldError> {
    crate::volume::check_sparse(&grid, basis, samples)?;
    let in_layers =
        |b: [usize; 3]| gy.contains(&(b[1] / SPARSE_GROUP)) && gz.contains(&(b[2] / SPARSE_GROUP));
    let (bricks, mut fit_report) =
        match basis {
            Basis::Trilinear => (
                samples
                    .stored()
                    .filter(|(b, _)| in_layers(*b))
                    .map(|(b, v)| (b, Box::new(*v)))
                    .collect(),
                report::report("none", None),
            ),
            Basis::Bspline2 => (
                sparse_interp::prefilter_groups(samples, QUADRATIC_POLE, gy, gz, report),
                report::report("prefilter", None),
            ),
            Basis::Bspline3 => (
                sparse_interp::prefilter_groups(samples, CUBIC_POLE, gy, gz, report),
                report::report("prefilter", None),
            ),
            Basis::Pg { .. } => return Err(FieldError::BadFit(
                "pseudo-Gaussian coefficients come from a global solve and cannot be fitted in \
                 parts; use a B-spline or trilinear basis"
                    .into(),
            )),
        };
    fit_report.method = FitMethod::Interp.name().to_string();
    Ok((bricks, fit_report))
}

/// Grid bricks of samples needed around a box of groups by [`interp_sparse_groups`].
pub fn sparse_reach(basis: Basis) -> usize {
    match basis {
        Basis::Bspline2 => sparse_interp::layer_reach(QUADRATIC_POLE),
        _ => sparse_interp::layer_reach(CUBIC_POLE),
    }
}

// Here rather than in `volume`, which the fits build on: pseudo-Gaussians interpolate by a fit.
impl CoefficientVolume {
    /// The field that interpolates `samples` (one per node, x fastest) in the given basis:
    /// B-splines by their exact prefilter, pseudo-Gaussians by an iterative collocation solve
    /// (see [`interp_samples`] for its report).
    pub fn interpolate(
        grid: Grid,
        basis: Basis,
        mut samples: Vec<f32>,
    ) -> Result<Self, FieldError> {
        check_inputs(&grid, basis, &samples)?;
        match basis {
            Basis::Trilinear => {}
            Basis::Bspline2 => prefilter_volume_with(&mut samples, grid.dims, QUADRATIC_POLE),
            Basis::Bspline3 => prefilter_volume_with(&mut samples, grid.dims, CUBIC_POLE),
            Basis::Pg { .. } => {
                let opts = FitOptions::default();
                return interp_samples(grid, basis, &samples, &opts).map(|(v, _)| v);
            }
        }
        CoefficientVolume::new(grid, basis, samples)
    }
}
