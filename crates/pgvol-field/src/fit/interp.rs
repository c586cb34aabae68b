//! Collocation at the nodes. B-splines: the exact prefilter. Pseudo-Gaussians: the node matrix
//! `A_ab = pg(|g_a − g_b|)` is symmetric, and positive definite only for some (n, r) — decided
//! from its lattice Fourier symbol — so CG where that holds, CGLS otherwise.

use glam::Vec3;
use pgvol_core::Grid;

use super::operator::{node_points, Operator};
use super::options::FitOptions;
use super::report::{report, FitReport};
use super::solve;
use super::weighted::{to_f32, weighted_solve, Rows};
use crate::basis::Basis;
use crate::kernel::PseudoGaussian;
use crate::prefilter::{prefilter_volume_with, CUBIC_POLE, QUADRATIC_POLE};

/// Smallest value of `Σ_m pg(|m|) cos(ω·m)` over `ω ∈ [0, π]³` (sampled on a 17³ lattice, which
/// includes the corners and edge midpoints where the minimum sits for these kernels). On a
/// finite grid the node matrix is a principal submatrix of the infinite one, so its eigenvalues
/// are bounded below by this.
pub fn lattice_symbol_min(n: u8, r: f32) -> f64 {
    let pg = PseudoGaussian { n, r };
    let reach = r.ceil() as i32;
    let mut taps = Vec::new();
    for z in -reach..=reach {
        for y in -reach..=reach {
            for x in -reach..=reach {
                let d2 = (x * x + y * y + z * z) as f32;
                let v = pg.value_sq(d2);
                if v != 0.0 {
                    taps.push(([x as f64, y as f64, z as f64], v as f64));
                }
            }
        }
    }
    let steps = 16;
    let mut best = f64::INFINITY;
    for a in 0..=steps {
        for b in 0..=a {
            for c in 0..=b {
                let w = [a, b, c].map(|s| std::f64::consts::PI * s as f64 / steps as f64);
                let s: f64 = taps
                    .iter()
                    .map(|(m, v)| v * (w[0] * m[0] + w[1] * m[1] + w[2] * m[2]).cos())
                    .sum();
                best = best.min(s);
            }
        }
    }
    best
}

/// Whether CG applies to the node collocation of this basis (with a margin for conditioning).
pub fn collocation_is_spd(basis: Basis) -> bool {
    match basis {
        Basis::Pg { n, r } => lattice_symbol_min(n, r) > 0.05,
        _ => true,
    }
}

pub(crate) fn fit_nodes(
    grid: &Grid,
    basis: Basis,
    samples: &[f32],
    options: &FitOptions,
) -> (Vec<f32>, FitReport) {
    let mut c = samples.to_vec();
    let mut rep = report("prefilter", None);
    match basis {
        Basis::Trilinear => rep.solver = "none".into(),
        Basis::Bspline2 => prefilter_volume_with(&mut c, grid.dims, QUADRATIC_POLE),
        Basis::Bspline3 => prefilter_volume_with(&mut c, grid.dims, CUBIC_POLE),
        Basis::Pg { .. } => {
            let points: Vec<Vec3> = node_points(grid.dims);
            let b: Vec<f64> = samples.iter().map(|&v| v as f64).collect();
            if collocation_is_spd(basis) {
                let op = Operator {
                    basis,
                    dims: grid.dims,
                    points: &points,
                    sqrt_weights: None,
                };
                let mut x = b.clone();
                let out = solve::cg(
                    |x| op.forward(x),
                    &b,
                    &mut x,
                    options.tolerance,
                    options.max_iterations,
                );
                return (to_f32(x), report("cg", Some(out)));
            }
            let (x, out) = weighted_solve(
                grid,
                basis,
                Rows {
                    points: &points,
                    targets: samples,
                    weights: None,
                },
                &b,
                0.0,
                options,
                None,
            );
            return (to_f32(x), report("cgls", Some(out)));
        }
    }
    (c, rep)
}

/// Coefficients to start iterative fits from: the node interpolant where it is cheap and
/// stable, the raw samples otherwise (pseudo-Gaussians whose node system is indefinite).
pub(crate) fn warm_start(
    grid: &Grid,
    basis: Basis,
    samples: &[f32],
    options: &FitOptions,
) -> Vec<f64> {
    let c = if collocation_is_spd(basis) {
        fit_nodes(grid, basis, samples, options).0
    } else {
        samples.to_vec()
    };
    c.into_iter().map(|v| v as f64).collect()
}
