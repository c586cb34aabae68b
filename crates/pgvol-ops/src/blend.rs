//! Algebraic blends between primaries (after Sipos' slides on implicit surface modelling):
//! Liming rounding, functional splines and I-patches, with their values renormalised near the
//! surface so that the result is again distance-like.
//!
//! Fields are negative inside. The blends of an edge between two solids `P₁ ≤ 0`, `P₂ ≤ 0`
//! replace the intersection `max(P₁, P₂)` where every bounding surface is negative (the region
//! the bounds cut off around the edge):
//! * Liming: `G = λ·C² − (1 − λ)·P₁·P₂`, the slides' `(1 − λ)·L₁·L₂ + λ·C²` with the sign
//!   turned so that it is negative inside; its zero set meets `P₁ = 0` and `P₂ = 0` tangentially
//!   where they cross `C = 0`;
//! * functional spline: `G = λ·ΠBᵢ² − (1 − λ)·ΠPᵢ` (two primaries), the same with one bound
//!   per primary.
//!
//! Inside the region the result is `max(Ĝ, min(P₁, P₂))`, which keeps the quadrant outside
//! both primaries outside. An I-patch `I = Σ wᵢ Pᵢ Π_{j≠i} Bⱼ² + w·ΠBᵢ²` is taken as it is: near
//! `Bᵢ = 0` it has the sign of `wᵢ Pᵢ`.
//!
//! `Ĝ = G / ‖∇G‖` (central differences) is the first-order distance to `G = 0`.

use glam::Vec3;

use crate::error::OpsError;

/// Liming's rounding of the edge between two primaries, cut by `c` (negative on the edge's
/// side); `lambda` in (0, 1) moves the blend away from the edge as it grows.
pub fn liming(p1: f32, p2: f32, c: f32, lambda: f32) -> f32 {
    lambda * c * c - (1.0 - lambda) * p1 * p2
}

/// The functional spline of two primaries with one bound each.
pub fn functional_spline(p: [f32; 2], b: [f32; 2], lambda: f32) -> f32 {
    lambda * (b[0] * b[0]) * (b[1] * b[1]) - (1.0 - lambda) * p[0] * p[1]
}

/// Refuses an I-patch whose bounds or weights do not pair one to one with its primaries:
/// [`ipatch`] and [`ipatch_terms`] take that as given.
pub fn check_ipatch(
    primaries: usize,
    bounds: usize,
    weights: Option<usize>,
) -> Result<(), OpsError> {
    if primaries < 2 || bounds != primaries {
        return Err(OpsError::BadParameter(format!(
            "an I-patch needs two or more primaries and one bound per primary, got {primaries} \
             primaries and {bounds} bounds"
        )));
    }
    match weights {
        Some(n) if n != primaries => Err(OpsError::BadParameter(format!(
            "an I-patch of {primaries} primaries needs {primaries} weights besides the bounds' \
             weight, got {n}"
        ))),
        _ => Ok(()),
    }
}

/// The I-patch of primaries `p` with bounds `b`, weights `w` and the bounds' weight `w0`; one
/// bound and one weight per primary (see [`check_ipatch`]).
pub fn ipatch(p: &[f32], b: &[f32], w: &[f32], w0: f32) -> f32 {
    let squares: Vec<f32> = b.iter().map(|x| x * x).collect();
    let all: f32 = squares.iter().product();
    let mut sum = w0 * all;
    for i in 0..p.len() {
        let others: f32 = (0..p.len())
            .filter(|&j| j != i)
            .map(|j| squares[j])
            .product();
        sum += w[i] * p[i] * others;
    }
    sum
}

/// The I-patch's terms at a point: `Pᵢ Π_{j≠i} Bⱼ²` for each i, then `ΠBᵢ²`; one bound per
/// primary (see [`check_ipatch`]).
pub fn ipatch_terms(p: &[f32], b: &[f32]) -> Vec<f64> {
    let mut terms: Vec<f64> = (0..p.len())
        .map(|i| {
            let mut t = p[i] as f64;
            for (j, &bj) in b.iter().enumerate() {
                if j != i {
                    t *= (bj as f64) * (bj as f64);
                }
            }
            t
        })
        .collect();
    terms.push(b.iter().map(|&x| (x as f64) * (x as f64)).product());
    terms
}

/// I-patch weights fitted to points meant to lie on the surface: least squares of the
/// patch's values at the points with the first weight held at 1 (the patch's scale is free).
/// `terms` holds [`ipatch_terms`] per point. Returns the weights and `w`.
pub fn fit_ipatch_weights(terms: &[Vec<f64>]) -> Result<(Vec<f32>, f32), OpsError> {
    let Some(first) = terms.first() else {
        return Err(OpsError::BadParameter(
            "fitting I-patch weights needs points".into(),
        ));
    };
    let n = first.len() - 1; // unknowns: w₂..wₙ and w
                             // Normal equations of min ‖A x + a₀‖², A the columns 1..=n, a₀ the first.
    let mut ata = vec![0.0f64; n * n];
    let mut atb = vec![0.0f64; n];
    for t in terms {
        for r in 0..n {
            atb[r] -= t[r + 1] * t[0];
            for c in 0..n {
                ata[r * n + c] += t[r + 1] * t[c + 1];
            }
        }
    }
    let x = solve_dense(&mut ata, &mut atb, n).ok_or_else(|| {
        OpsError::BadParameter(
            "the points do not determine the I-patch's weights (too few, or all on one \
             primary); give points spread over the blend"
                .into(),
        )
    })?;
    let mut w = vec![1.0f32];
    w.extend(x[..n - 1].iter().map(|&v| v as f32));
    Ok((w, x[n - 1] as f32))
}

/// Gaussian elimination with partial pivoting; `None` when singular.
fn solve_dense(a: &mut [f64], b: &mut [f64], n: usize) -> Option<Vec<f64>> {
    let scale = a
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(f64::MIN_POSITIVE);
    for k in 0..n {
        let pivot = (k..n).max_by(|&i, &j| a[i * n + k].abs().total_cmp(&a[j * n + k].abs()))?;
        if a[pivot * n + k].abs() <= 1e-12 * scale {
            return None;
        }
        for c in 0..n {
            a.swap(k * n + c, pivot * n + c);
        }
        b.swap(k, pivot);
        for i in k + 1..n {
            let f = a[i * n + k] / a[k * n + k];
            for c in k..n {
                a[i * n + c] -= f * a[k * n + c];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let s: f64 = (k + 1..n).map(|c| a[k * n + c] * x[c]).sum();
        x[k] = (b[k] - s) / a[k * n + k];
    }
    Some(x)
}

/// `g(p) / ‖∇g(p)‖` with the gradient by central differences of step `step`: the first-order
/// distance to the zero set of `g`.
pub fn renormalised(g: &impl Fn(Vec3) -> f32, p: Vec3, step: f32) -> f32 {
    let v = g(p);
    let d = |e: Vec3| (g(p + e) - g(p - e)) / (2.0 * step);
    let grad = Vec3::new(d(Vec3::X * step), d(Vec3::Y * step), d(Vec3::Z * step));
    let l = grad.length();
    if l > 1e-12 {
        v / l
    } else {
        v.signum() * f32::MAX
    }
}

/// A blend `g` of the edge between `p1` and `p2` inside the region where `inside_region`
/// holds, and their sharp intersection elsewhere (see the module's documentation).
pub fn edge_blend(
    p1: f32,
    p2: f32,
    inside_region: bool,
    renormalised_blend: impl FnOnce() -> f32,
) -> f32 {
    if inside_region {
        renormalised_blend().max(p1.min(p2))
    } else {
        p1.max(p2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn liming_is_tangent_to_the_primaries_on_the_cut() {
        // P₁ = x, P₂ = y (solid: the quadrant x, y ≤ 0), C = x + y + 1 cuts the corner.
        let g = |p: Vec3| liming(p.x, p.y, p.x + p.y + 1.0, 0.5);
        // On the cut, the blend's zero set meets the primaries: (−1, 0) and (0, −1).
        assert!(g(Vec3::new(-1.0, 0.0, 0.0)).abs() < 1e-6);
        assert!(g(Vec3::new(0.0, -1.0, 0.0)).abs() < 1e-6);
        // Tangent there: the gradient is along P₂'s normal at (−1, 0).
        let n = Vec3::new(
            g(Vec3::new(-0.999, 0.0, 0.0)) - g(Vec3::new(-1.001, 0.0, 0.0)),
            g(Vec3::new(-1.0, 0.001, 0.0)) - g(Vec3::new(-1.0, -0.001, 0.0)),
            0.0,
        );
        assert!(n.normalize().dot(Vec3::Y) > 0.999, "{n}");
        // The corner itself is cut off: outside.
        assert!(g(Vec3::new(-0.1, -0.1, 0.0)) > 0.0);
        assert!(g(Vec3::new(-0.9, -0.9, 0.0)) < 0.0);
    }

    #[test]
    fn ipatch_weights_are_recovered_from_points() {
        // Two planes x = 0, y = 0 with bounds x − 1, y − 1; known weights (1, 2, w = −0.5).
        let (w, w0) = (vec![1.0f32, 2.0], -0.5f32);
        let f = |p: Vec3| {
            let (pp, b) = ([p.x, p.y], [p.x - 1.0, p.y - 1.0]);
            ipatch(&pp, &b, &w, w0)
        };
        // Points on the patch: on vertical lines, the first sign change of y ↦ f.
        let mut terms = Vec::new();
        for k in 1..16 {
            let x = k as f32 / 8.0 - 0.9;
            let at = |y: f32| f(Vec3::new(x, y, 0.0));
            let mut y0 = -3.0f32;
            while at(y0).signum() == at(y0 + 0.01).signum() && y0 < 0.98 {
                y0 += 0.01;
            }
            let (mut a, mut b) = (y0, y0 + 0.01);
            for _ in 0..50 {
                let m = 0.5 * (a + b);
                if at(m).signum() == at(a).signum() {
                    a = m;
                } else {
                    b = m;
                }
            }
            let y = 0.5 * (a + b);
            if at(y).abs() > 1e-4 {
                continue;
            }
            terms.push(ipatch_terms(&[x, y], &[x - 1.0, y - 1.0]));
        }
        assert!(terms.len() >= 3, "{} points", terms.len());
        let (fw, fw0) = fit_ipatch_weights(&terms).unwrap();
        assert!(
            (fw[1] - 2.0).abs() < 1e-3 && (fw0 + 0.5).abs() < 1e-3,
            "{fw:?} {fw0}"
        );
        assert!(fit_ipatch_weights(&terms[..1]).is_err());
    }

    #[test]
    fn ipatches_without_a_bound_per_primary_are_refused() {
        assert!(check_ipatch(2, 2, None).is_ok() && check_ipatch(3, 3, Some(3)).is_ok());
        let e = check_ipatch(2, 1, None).unwrap_err().to_string();
        assert!(e.contains("2 primaries and 1 bounds"), "{e}");
        assert!(check_ipatch(1, 1, None).is_err());
        assert!(check_ipatch(2, 3, None).is_err());
        let e = check_ipatch(2, 2, Some(1)).unwrap_err().to_string();
        assert!(e.contains("needs 2 weights"), "{e}");
    }

    #[test]
    fn renormalising_a_scaled_sphere_gives_its_distance() {
        let g = |p: Vec3| 3.0 * (p.length_squared() - 1.0);
        let v = renormalised(&g, Vec3::new(1.05, 0.0, 0.0), 1e-3);
        assert!((v - 0.05).abs() < 0.003, "{v}");
    }
}
