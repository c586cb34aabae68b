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
//! * functional spline of n primaries and m bounds: `G = λ·ΠBⱼ² − (1 − λ)·Π(−Pᵢ)`.
//!
//! Inside the region the result is at least the second-largest primary (`min(P₁, P₂)` for two),
//! which keeps what lies outside two or more primaries outside. An I-patch
//! `I = Σ wᵢ Pᵢ Π_{j≠i} Bⱼᵉ + w·ΠBᵢᵉ`, `e = n + 1` for Gⁿ continuity, is taken as it is: near
//! `Bᵢ = 0` it has the sign of `wᵢ Pᵢ`.
//!
//! `Ĝ = G / ‖∇G‖` (central differences) is the first-order distance to `G = 0`.

mod ipatch;
mod spline;
mod weights;

use glam::Vec3;

pub use ipatch::{check_ipatch, ipatch, ipatch_terms, Continuity, MAX_CONTINUITY};
use spline::second_largest;
pub use spline::{check_spline, functional_spline};
pub use weights::{fit_ipatch_weights, weight_through_point};

/// Liming's rounding of the edge between two primaries, cut by `c` (negative on the edge's
/// side); `lambda` in (0, 1) moves the blend away from the edge as it grows.
pub fn liming(p1: f32, p2: f32, c: f32, lambda: f32) -> f32 {
    lambda * c * c - (1.0 - lambda) * p1 * p2
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

/// A blend of the edge (or vertex) where the primaries `p` meet, inside the region where
/// `inside_region` holds, and their sharp intersection elsewhere (see the module's
/// documentation).
pub fn edge_blend(p: &[f32], inside_region: bool, renormalised_blend: impl FnOnce() -> f32) -> f32 {
    if inside_region {
        renormalised_blend().max(second_largest(p))
    } else {
        p.iter().copied().fold(f32::NEG_INFINITY, f32::max)
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
    fn renormalising_a_scaled_sphere_gives_its_distance() {
        let g = |p: Vec3| 3.0 * (p.length_squared() - 1.0);
        let v = renormalised(&g, Vec3::new(1.05, 0.0, 0.0), 1e-3);
        assert!((v - 0.05).abs() < 0.003, "{v}");
    }
}
