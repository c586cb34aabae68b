//! The paper's fit: one collocation point per node, moved to the nearest point of the isosurface
//! `SDF = q · z_step` (q the nearest integer), so the zero surface and its offsets are hit
//! exactly; a square, non-symmetric system solved by CGLS. `z_step` may be searched for.

use glam::Vec3;
use pgvol_core::progress::Span;
use pgvol_core::Grid;

use super::golden::golden_section;
use super::node_sdf::{project, NodeSdf};
use super::operator::Operator;
use super::options::FitOptions;
use super::report::{report, FitReport};
use super::weighted::{to_f32, weighted_solve, Rows};
use crate::basis::Basis;
use crate::distance::SignedDistance;
use crate::volume::FieldError;

/// The longest isosurface step, in grid spacings. The method requires the step to be at most
/// the grid spacing k, so that every node has an isosurface within k/2 and its collocation
/// point stays near it; longer steps leave nodes between isosurfaces far apart.
pub const MAX_Z_STEP: f32 = 1.0;

pub(crate) fn fit(
    grid: &Grid,
    basis: Basis,
    nodes: &NodeSdf,
    sdf: &dyn SignedDistance,
    z_step: Option<f32>,
    options: &FitOptions,
    span: Option<Span>,
) -> Result<(Vec<f32>, FitReport), FieldError> {
    let warm = super::interp::warm_start(grid, basis, &nodes.distance, options);
    // Every solve of the search and the final one take an equal part of the progress.
    let solves = match z_step {
        Some(_) => 1,
        None => options.z_step_evaluations.max(3) + 1,
    };
    let part = |i: usize| {
        let i = i.min(solves - 1) as f64;
        span.map(|s| s.part(i / solves as f64, (i + 1.0) / solves as f64))
    };
    let z = match z_step {
        Some(z) if z.is_finite() && z > 0.0 && z <= MAX_Z_STEP => z,
        Some(z) => {
            return Err(FieldError::BadFit(format!(
                "the isosurface step must be in (0, {MAX_Z_STEP}] grid spacings, got {z}: a \
                 longer step moves nodes farther than half a spacing to their isosurface, \
                 which the method does not allow"
            )))
        }
        None => search(grid, basis, nodes, sdf, &warm, options, &part),
    };
    let last = part(solves - 1);
    let (c, outcome) = solve_step(grid, basis, nodes, sdf, z, &warm, options, last);
    let mut rep = report("cgls", Some(outcome));
    rep.z_step = Some(z);
    Ok((to_f32(c), rep))
}

/// Collocation points and targets for step `z` (spacings). A point that would leave the basis
/// function's support or the grid box stays on its node with the node's SDF as target.
fn points(
    grid: &Grid,
    basis: Basis,
    nodes: &NodeSdf,
    sdf: &dyn SignedDistance,
    z: f32,
) -> (Vec<Vec3>, Vec<f32>) {
    let k = grid.spacing;
    let reach = basis.support() * k * 0.999;
    let hi = grid.max_corner();
    let [nx, ny, _] = grid.dims;
    let mut pts = Vec::with_capacity(grid.len());
    let mut tgt = Vec::with_capacity(grid.len());
    for (idx, (&d, &n)) in nodes.distance.iter().zip(&nodes.gradient).enumerate() {
        let g = grid.point(idx % nx, (idx / nx) % ny, idx / (nx * ny));
        let t = (d / (z * k)).round() * z * k;
        let p = project(sdf, g, d, n, t);
        let ok = p.is_finite()
            && p.distance(g) < reach
            && p.cmpge(grid.origin).all()
            && p.cmple(hi).all();
        let (p, t) = if ok { (p, t) } else { (g, d) };
        pts.push(grid.to_grid(p));
        tgt.push(t);
    }
    (pts, tgt)
}

#[allow(clippy::too_many_arguments)]
fn solve_step(
    grid: &Grid,
    basis: Basis,
    nodes: &NodeSdf,
    sdf: &dyn SignedDistance,
    z: f32,
    warm: &[f64],
    options: &FitOptions,
    span: Option<Span>,
) -> (Vec<f64>, super::solve::SolveOutcome) {
    let (pts, tgt) = points(grid, basis, nodes, sdf, z);
    weighted_solve(
        grid,
        basis,
        Rows {
            points: &pts,
            targets: &tgt,
            weights: None,
        },
        warm,
        0.0,
        options,
        span,
    )
}

/// Golden-section search of `z_step` in [0.05, [`MAX_Z_STEP`]] spacings for the smallest RMS of `f − SDF` at
/// the cell centres within two spacings of the surface and at the nodes' nearest surface points.
fn search<'a>(
    grid: &Grid,
    basis: Basis,
    nodes: &NodeSdf,
    sdf: &dyn SignedDistance,
    warm: &[f64],
    options: &FitOptions,
    part: &dyn Fn(usize) -> Option<Span<'a>>,
) -> f32 {
    let k = grid.spacing;
    let [nx, ny, nz] = grid.dims;
    let mut check = Vec::new();
    let mut want = Vec::new();
    for (idx, (&d, &n)) in nodes.distance.iter().zip(&nodes.gradient).enumerate() {
        if d.abs() >= 2.0 * k {
            continue;
        }
        let (i, j, l) = (idx % nx, (idx / nx) % ny, idx / (nx * ny));
        let g = grid.point(i, j, l);
        let s = project(sdf, g, d, n, 0.0);
        if s.is_finite() && s.cmpge(grid.origin).all() && s.cmple(grid.max_corner()).all() {
            check.push(grid.to_grid(s));
            want.push(0.0f64);
        }
        if i + 1 < nx && j + 1 < ny && l + 1 < nz {
            let c = g + Vec3::splat(0.5 * k);
            check.push(grid.to_grid(c));
            want.push(sdf.distance(c) as f64);
        }
    }
    let op = Operator {
        basis,
        dims: grid.dims,
        points: &check,
        sqrt_weights: None,
    };
    let solved = std::cell::Cell::new(0);
    let cost = |z: f32| {
        let span = part(solved.replace(solved.get() + 1));
        let (c, _) = solve_step(grid, basis, nodes, sdf, z, warm, options, span);
        let f = op.forward(&c);
        let e: f64 = f.iter().zip(&want).map(|(f, w)| (f - w) * (f - w)).sum();
        let e = (e / want.len().max(1) as f64).sqrt();
        if e.is_finite() {
            e
        } else {
            f64::INFINITY
        }
    };
    golden_section(
        |z| cost(z as f32),
        0.05,
        MAX_Z_STEP as f64,
        options.z_step_evaluations,
    ) as f32
}
