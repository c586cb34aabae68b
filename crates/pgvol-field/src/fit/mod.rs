//! Finding coefficients from a signed distance function, matrix-free: `interp` (collocation at
//! the nodes), `iso` (the paper's points moved onto isosurfaces of the SDF) and `wls` (weighted
//! least squares around the zero surface).

mod band_operator;
mod band_rows;
mod golden;
mod interp;
mod iso;
mod layer_blocks;
mod node_values;
pub mod operator;
mod row_kernels;
mod row_window;
pub mod solve;
mod vector;
mod wls;

pub use golden::golden_section;
pub use interp::{collocation_is_spd, lattice_symbol_min};
pub use node_values::node_values;
pub use wls::wls_band;

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::volume::check_inputs;
use crate::{Basis, CoefficientVolume, FieldError, Grid};

/// A signed distance function (negative inside) with its gradient, the unit direction away from
/// the closest surface point.
pub trait SignedDistance: Sync {
    fn distance(&self, p: Vec3) -> f32;
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3);
}

/// Adapts a closure returning `(distance, gradient)` to [`SignedDistance`].
pub struct SdfFn<F>(pub F);

impl<F: Fn(Vec3) -> (f32, Vec3) + Sync> SignedDistance for SdfFn<F> {
    fn distance(&self, p: Vec3) -> f32 {
        (self.0)(p).0
    }
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        (self.0)(p)
    }
}

/// Closest points on the surface being fitted: what the banded fit needs once the signed
/// distances at the nodes are known (no sign queries).
pub trait ClosestPoint: Sync {
    /// The surface point closest to `p`; the caller knows one lies within `max_distance`, which
    /// a search may use to prune. `None` when there is none.
    fn closest_point(&self, p: Vec3, max_distance: f32) -> Option<Vec3>;
}

/// Adapts a closure `(p, max_distance) -> closest point` to [`ClosestPoint`].
pub struct ClosestFn<F>(pub F);

impl<F: Fn(Vec3, f32) -> Option<Vec3> + Sync> ClosestPoint for ClosestFn<F> {
    fn closest_point(&self, p: Vec3, max_distance: f32) -> Option<Vec3> {
        (self.0)(p, max_distance)
    }
}

/// The closest points of a [`SignedDistance`]: one step back along its gradient.
pub struct SurfaceOf<'a>(pub &'a dyn SignedDistance);

impl ClosestPoint for SurfaceOf<'_> {
    fn closest_point(&self, p: Vec3, _max_distance: f32) -> Option<Vec3> {
        let (d, n) = self.0.distance_gradient(p);
        let c = p - d * n;
        c.is_finite().then_some(c)
    }
}

/// How the coefficients are found.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FitMethod {
    /// The field equals the SDF at every node.
    Interp,
    /// The paper's choice: each node's collocation point moved to the nearest point of the
    /// isosurface `SDF = q · z_step` (q the nearest integer), `z_step` in grid spacings; `None`
    /// searches for the step with the smallest error near the surface.
    Iso { z_step: Option<f32> },
    /// Weighted least squares: band nodes projected onto the zero surface (weight
    /// `surface_weight`) and onto `±k/2` (`offset_weight`); only coefficients these samples
    /// reach are unknowns, each held to its `Interp` value with weight `node_weight`; the other
    /// coefficients keep their `Interp` values.
    Wls,
}

impl FitMethod {
    pub fn name(self) -> &'static str {
        match self {
            FitMethod::Interp => "interp",
            FitMethod::Iso { .. } => "iso",
            FitMethod::Wls => "wls",
        }
    }
}

/// Solver and sampling settings.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// Relative residual at which an iterative solve stops.
    pub tolerance: f64,
    pub max_iterations: usize,
    /// Half-width of the band of nodes that give surface samples to `Wls`, in grid spacings.
    pub band: f32,
    /// `Wls` weights: samples on the zero surface, samples k/2 off it, and the anchor holding
    /// each unknown coefficient to its `Interp` value.
    pub surface_weight: f32,
    pub offset_weight: f32,
    pub node_weight: f32,
    /// Tikhonov damping of the change from the warm start (`Wls`), relative to unit weights.
    pub damping: f64,
    /// `Wls` also stops once an iteration lowers its objective by at most this fraction of what
    /// the iterations so far did: its system is inconsistent, so the data residual never reaches
    /// `tolerance`, and the normal-equation residual left is in directions the fit barely sees.
    pub stall: f64,
    /// Fits tried by the `z_step` search of `Iso`.
    pub z_step_evaluations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            tolerance: 1e-5,
            max_iterations: 400,
            band: 1.5,
            surface_weight: 1.0,
            offset_weight: 0.5,
            // An anchor on each unknown, which damps alternating patterns that node rows would
            // leave free, so it is weaker than node rows were: at 128³ (Chamfer-L1, iterations)
            // 0.1 gave fandisk 0.0056 %, 5; 0.005 gave 0.0051 %, 9; 0.001 gave 0.0050 %, 11.
            node_weight: 0.005,
            damping: 1e-3,
            stall: 0.01,
            z_step_evaluations: 10,
        }
    }
}

/// What a fit did and how well its solver did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    pub method: String,
    /// `"prefilter"`, `"cg"`, `"cgls"` or `"none"`.
    pub solver: String,
    /// Iterations of the last solve (0 for the direct prefilter).
    pub iterations: usize,
    /// Relative residual `‖A c − b‖ / ‖b‖` of the (weighted) system at the end.
    pub residual: f64,
    pub converged: bool,
    pub seconds: f64,
    /// Nodes farther than one spacing from the surface where the field's sign disagrees with
    /// the SDF's: extra surface pieces.
    pub spurious_sign_changes: usize,
    /// The isosurface step used by `Iso`, in grid spacings.
    pub z_step: Option<f32>,
    /// Relative residual of the warm start, for iterative fits that have one (`Wls`): the solve
    /// took it to `residual`.
    #[serde(default)]
    pub initial_residual: Option<f64>,
    /// The normal-equation residual at the end relative to its start (least-squares solves).
    #[serde(default)]
    pub normal_residual: Option<f64>,
    /// Unknown coefficients and sample rows of the solve (0 for direct fits).
    #[serde(default)]
    pub unknowns: usize,
    #[serde(default)]
    pub rows: usize,
    /// Where the time went, in seconds.
    #[serde(default)]
    pub stages: FitStages,
}

/// Seconds per stage of a fit; stages a fit does not have stay 0.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FitStages {
    /// Interpolating the node samples (the fit itself for `Interp`, the warm start otherwise).
    pub warm_start: f64,
    /// Closest points and offset distances for the sample rows.
    pub projections: f64,
    /// Finding the unknowns and the preconditioner.
    pub setup: f64,
    pub solve: f64,
    /// Counting spurious sign changes.
    pub check: f64,
}

/// Fits a coefficient volume on `grid` to the signed distance `sdf`.
pub fn fit(
    grid: Grid,
    basis: Basis,
    method: FitMethod,
    sdf: &dyn SignedDistance,
    options: &FitOptions,
) -> Result<(CoefficientVolume, FitReport), FieldError> {
    let start = Instant::now();
    let nodes = NodeSdf::sample(&grid, sdf);
    check_inputs(&grid, basis, &nodes.distance)?;
    let (coeffs, mut report) = match method {
        FitMethod::Interp => interp::fit_nodes(&grid, basis, &nodes.distance, options),
        FitMethod::Iso { z_step } => iso::fit(&grid, basis, &nodes, sdf, z_step, options)?,
        FitMethod::Wls => wls::fit(&grid, basis, &nodes.distance, &SurfaceOf(sdf), options),
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

/// Counts nodes with `|SDF| > k` where the field's sign differs from the SDF's.
pub fn spurious_sign_changes(volume: &CoefficientVolume, node_sdf: &[f32]) -> usize {
    let k = volume.grid.spacing;
    node_values::count_nodes(volume, |f, i| {
        let d = node_sdf[i];
        d.abs() > k && (f < 0.0) != (d < 0.0)
    })
}

/// The SDF and its gradient at every node (x fastest).
pub(crate) struct NodeSdf {
    pub distance: Vec<f32>,
    pub gradient: Vec<Vec3>,
}

impl NodeSdf {
    fn sample(grid: &Grid, sdf: &dyn SignedDistance) -> NodeSdf {
        let [nx, ny, _] = grid.dims;
        let pairs: Vec<(f32, Vec3)> = (0..grid.len())
            .into_par_iter()
            .map(|idx| {
                let (i, j, k) = (idx % nx, (idx / nx) % ny, idx / (nx * ny));
                sdf.distance_gradient(grid.point(i, j, k))
            })
            .collect();
        let (distance, gradient) = pairs.into_iter().unzip();
        NodeSdf { distance, gradient }
    }
}

/// Moves `p` along the SDF gradient until the SDF equals `target` (exact for a true distance
/// function away from its medial axis; two steps absorb curvature of an approximate one).
pub(crate) fn project(sdf: &dyn SignedDistance, p: Vec3, d: f32, n: Vec3, target: f32) -> Vec3 {
    let mut q = p - (d - target) * n;
    for _ in 0..2 {
        let (dq, nq) = sdf.distance_gradient(q);
        if (dq - target).abs() < 1e-7 || !nq.is_finite() {
            break;
        }
        q -= (dq - target) * nq;
    }
    q
}

/// Sample points (grid coordinates), their target values and optional weights.
pub(crate) struct Rows<'a> {
    pub points: &'a [Vec3],
    pub targets: &'a [f32],
    pub weights: Option<&'a [f64]>,
}

/// Least squares `min ‖W^½ (A c − t)‖² + λ² ‖y‖²` with `c = c0 + D y`, D the Jacobi scaling of
/// the columns, by CGLS. Returns the coefficients and the solve outcome.
pub(crate) fn weighted_solve(
    grid: &Grid,
    basis: Basis,
    rows: Rows<'_>,
    warm: &[f64],
    damping: f64,
    options: &FitOptions,
) -> (Vec<f64>, solve::SolveOutcome) {
    let Rows {
        points,
        targets,
        weights,
    } = rows;
    let sqrt_w: Option<Vec<f64>> = weights.map(|w| w.iter().map(|w| w.sqrt()).collect());
    let op = operator::Operator {
        basis,
        dims: grid.dims,
        points,
        sqrt_weights: sqrt_w.as_deref(),
    };
    let a0 = op.forward(warm);
    let b: Vec<f64> = targets
        .iter()
        .enumerate()
        .map(|(i, &t)| t as f64 * sqrt_w.as_ref().map_or(1.0, |w| w[i]) - a0[i])
        .collect();
    let scale: Vec<f64> = op
        .column_norms_sq()
        .iter()
        .map(|&s| if s > 1e-12 { 1.0 / s.sqrt() } else { 0.0 })
        .collect();
    let fwd = |y: &[f64]| {
        let c: Vec<f64> = y.iter().zip(&scale).map(|(y, s)| y * s).collect();
        op.forward(&c)
    };
    let adj = |r: &[f64]| {
        let mut g = op.adjoint(r);
        for (g, s) in g.iter_mut().zip(&scale) {
            *g *= s;
        }
        g
    };
    let (y, outcome) = solve::cgls(
        fwd,
        adj,
        &b,
        op.cols(),
        damping,
        options.tolerance,
        options.max_iterations,
    );
    let c = warm
        .iter()
        .zip(y.iter().zip(&scale))
        .map(|(c0, (y, s))| c0 + y * s)
        .collect();
    (c, outcome)
}

pub(crate) fn to_f32(c: Vec<f64>) -> Vec<f32> {
    c.into_iter().map(|v| v as f32).collect()
}

pub(crate) fn report(solver: &str, outcome: Option<solve::SolveOutcome>) -> FitReport {
    let o = outcome.unwrap_or(solve::SolveOutcome {
        iterations: 0,
        residual: 0.0,
        normal_residual: 0.0,
        converged: true,
    });
    FitReport {
        method: String::new(),
        solver: solver.to_string(),
        iterations: o.iterations,
        residual: o.residual,
        converged: o.converged,
        seconds: 0.0,
        spurious_sign_changes: 0,
        z_step: None,
        initial_residual: None,
        normal_residual: None,
        unknowns: 0,
        rows: 0,
        stages: FitStages::default(),
    }
}
