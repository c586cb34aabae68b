//! The damped, weighted least-squares solve shared by the collocation fits.

use glam::Vec3;
use pgvol_core::progress::Span;
use pgvol_core::Grid;

use super::options::FitOptions;
use super::{operator, solve};
use crate::basis::Basis;

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
    span: Option<Span>,
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
    let limits = solve::Limits {
        tol: options.tolerance,
        stall: 0.0,
        max_iterations: options.max_iterations,
    };
    let (y, outcome) = solve::cgls_within(fwd, adj, &b, op.cols(), damping, limits, span);
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
