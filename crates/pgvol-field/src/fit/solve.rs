//! Krylov solvers on operators given as closures: conjugate gradients for symmetric positive
//! definite systems, CGLS for everything else (least squares, with optional damping).

pub use super::vector::dot;
use pgvol_core::progress::Span;

use super::vector::{axpy, axpy_norm_sq, xpby};

/// How a solve ended.
#[derive(Clone, Copy, Debug)]
pub struct SolveOutcome {
    pub iterations: usize,
    /// `‖A x − b‖ / ‖b‖` at the end (the damping term excluded).
    pub residual: f64,
    /// Least squares: the normal-equation residual `‖Aᵀ(b − A x) − λ² x‖` relative to its start
    /// (what CGLS drives to zero when the system is inconsistent); 0 for CG.
    pub normal_residual: f64,
    pub converged: bool,
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

/// Conjugate gradients for `A x = b`, `A` symmetric positive definite, from the initial `x`.
/// Stops when `‖r‖ ≤ tol ‖b‖`.
pub fn cg(
    apply: impl Fn(&[f64]) -> Vec<f64>,
    b: &[f64],
    x: &mut [f64],
    tol: f64,
    max_iterations: usize,
) -> SolveOutcome {
    let bn = norm(b).max(f64::MIN_POSITIVE);
    let ax = apply(x);
    let mut r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let mut p = r.clone();
    let mut rr = dot(&r, &r);
    let mut it = 0;
    while rr.sqrt() > tol * bn && it < max_iterations {
        let ap = apply(&p);
        let pap = dot(&p, &ap);
        if pap <= 0.0 || !pap.is_finite() {
            break; // not positive definite along p: report what we have
        }
        let alpha = rr / pap;
        axpy(x, alpha, &p);
        let rr_new = axpy_norm_sq(&mut r, -alpha, &ap);
        let beta = rr_new / rr;
        rr = rr_new;
        xpby(&mut p, &r, beta);
        it += 1;
    }
    let residual = rr.sqrt() / bn;
    SolveOutcome {
        iterations: it,
        residual,
        normal_residual: 0.0,
        converged: residual <= tol,
    }
}

/// CGLS for `min ‖A x − b‖² + λ² ‖x‖²` from `x = 0`. Stops when the data residual falls below
/// `tol ‖b‖` (consistent systems) or the normal-equation residual below `tol` times its start
/// (least squares).
pub fn cgls(
    forward: impl FnMut(&[f64]) -> Vec<f64>,
    adjoint: impl FnMut(&[f64]) -> Vec<f64>,
    b: &[f64],
    cols: usize,
    damping: f64,
    tol: f64,
    max_iterations: usize,
) -> (Vec<f64>, SolveOutcome) {
    cgls_with_stall(forward, adjoint, b, cols, damping, tol, 0.0, max_iterations)
}

/// [`cgls`] that also stops once an iteration lowers the objective by at most `stall` times
/// what all iterations so far have: for inconsistent least squares whose remaining
/// normal-equation residual lies in directions that barely change the fit.
#[allow(clippy::too_many_arguments)]
pub fn cgls_with_stall(
    forward: impl FnMut(&[f64]) -> Vec<f64>,
    adjoint: impl FnMut(&[f64]) -> Vec<f64>,
    b: &[f64],
    cols: usize,
    damping: f64,
    tol: f64,
    stall: f64,
    max_iterations: usize,
) -> (Vec<f64>, SolveOutcome) {
    let limits = Limits {
        tol,
        stall,
        max_iterations,
    };
    cgls_within(forward, adjoint, b, cols, damping, limits, None)
}

/// When an iterative solve stops: see [`cgls_with_stall`].
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    pub tol: f64,
    pub stall: f64,
    pub max_iterations: usize,
}

/// The fraction of a solve done after `it` iterations: the larger of the iterations used and
/// the decades of residual gained towards `tol`, since either may end it.
fn fraction_done(it: usize, max_iterations: usize, gained: f64, tol: f64) -> f64 {
    let by_iterations = it as f64 / max_iterations.max(1) as f64;
    let by_residual = gained.max(1.0).ln() / (1.0 / tol.clamp(1e-300, 0.5)).ln();
    by_iterations.max(by_residual).min(1.0)
}

/// [`cgls_with_stall`] within `limits`, reporting the fraction done through `span` after each
/// iteration.
pub fn cgls_within(
    mut forward: impl FnMut(&[f64]) -> Vec<f64>,
    mut adjoint: impl FnMut(&[f64]) -> Vec<f64>,
    b: &[f64],
    cols: usize,
    damping: f64,
    limits: Limits,
    span: Option<Span>,
) -> (Vec<f64>, SolveOutcome) {
    let Limits {
        tol,
        stall,
        max_iterations,
    } = limits;
    let mut shown = 0.0f64;
    let l2 = damping * damping;
    // ‖r‖² comes out of the update of r, so the stopping test needs no pass of its own.
    let mut rr = dot(b, b);
    let bn = rr.sqrt().max(f64::MIN_POSITIVE);
    let mut x = vec![0.0f64; cols];
    let mut r = b.to_vec();
    let mut s = adjoint(&r);
    let s0 = norm(&s).max(f64::MIN_POSITIVE);
    let mut p = s.clone();
    let mut gamma = dot(&s, &s);
    let mut it = 0;
    let (mut gain, mut total_gain) = (f64::INFINITY, 0.0f64);
    let done = |rr: f64, gamma: f64, gain: f64, total: f64| {
        rr.sqrt() <= tol * bn || gamma.sqrt() <= tol * s0 || gain <= stall * total
    };
    while !done(rr, gamma, gain, total_gain) && it < max_iterations {
        let q = forward(&p);
        let delta = dot(&q, &q) + l2 * dot(&p, &p);
        if delta <= 0.0 || !delta.is_finite() {
            break;
        }
        let alpha = gamma / delta;
        // The objective falls by exactly α γ per step.
        gain = alpha * gamma;
        total_gain += gain;
        axpy(&mut x, alpha, &p);
        rr = axpy_norm_sq(&mut r, -alpha, &q);
        s = adjoint(&r);
        let gamma_new = if l2 > 0.0 {
            axpy_norm_sq(&mut s, -l2, &x)
        } else {
            dot(&s, &s)
        };
        let beta = gamma_new / gamma;
        gamma = gamma_new;
        xpby(&mut p, &s, beta);
        it += 1;
        if let Some(span) = &span {
            let gained = (bn / rr.sqrt()).max(s0 / gamma.sqrt());
            let f = fraction_done(it, max_iterations, gained, tol).max(shown);
            if f >= shown + 0.005 {
                shown = f;
                span.report(f);
            }
        }
    }
    if let Some(span) = &span {
        span.report(1.0);
    }
    let converged = done(rr, gamma, gain, total_gain);
    let residual = rr.sqrt() / bn;
    (
        x,
        SolveOutcome {
            iterations: it,
            residual,
            normal_residual: gamma.sqrt() / s0,
            converged,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1D Laplacian-like SPD tridiagonal matrix.
    fn tri(x: &[f64]) -> Vec<f64> {
        let n = x.len();
        (0..n)
            .map(|i| {
                let l = if i > 0 { x[i - 1] } else { 0.0 };
                let r = if i + 1 < n { x[i + 1] } else { 0.0 };
                3.0 * x[i] - l - r
            })
            .collect()
    }

    #[test]
    fn cg_solves_an_spd_system() {
        let b: Vec<f64> = (0..50).map(|i| (i as f64).sin()).collect();
        let mut x = vec![0.0; 50];
        let out = cg(tri, &b, &mut x, 1e-10, 200);
        assert!(out.converged, "{out:?}");
        let ax = tri(&x);
        assert!(ax.iter().zip(&b).all(|(a, b)| (a - b).abs() < 1e-8));
    }

    #[test]
    fn cgls_solves_an_overdetermined_system() {
        // Rows: the tridiagonal matrix stacked over the identity; normal equations by hand.
        let fwd = |x: &[f64]| {
            let mut v = tri(x);
            v.extend_from_slice(x);
            v
        };
        let adj = |r: &[f64]| {
            let (a, b) = r.split_at(r.len() / 2);
            tri(a).iter().zip(b).map(|(x, y)| x + y).collect::<Vec<_>>()
        };
        let b: Vec<f64> = (0..60).map(|i| ((i * 7) % 5) as f64).collect();
        let (x, out) = cgls(fwd, adj, &b, 30, 0.0, 1e-12, 500);
        assert!(out.converged);
        // Optimality: Aᵀ(b − A x) = 0.
        let ax = fwd(&x);
        let r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
        assert!(adj(&r).iter().all(|g| g.abs() < 1e-8));
    }
}
