//! Functional splines of n primaries and m bounds, the slides'
//! `F = (1 − λ)·ΠPᵢ + λ·ΠBⱼ²` turned so that it is negative inside every primary.

use crate::error::OpsError;

/// Refuses a functional spline without an edge to round (fewer than two primaries) or without
/// a bound to cut it off.
pub fn check_spline(primaries: usize, bounds: usize) -> Result<(), OpsError> {
    if primaries < 2 || bounds < 1 {
        return Err(OpsError::BadParameter(format!(
            "a functional spline needs two or more primaries and at least one bound, got \
             {primaries} primaries and {bounds} bounds"
        )));
    }
    Ok(())
}

/// `G = λ·ΠBⱼ² − (1 − λ)·Π(−Pᵢ)`: `Π(−Pᵢ)` is positive inside every primary whatever their
/// number, and for two primaries it is `P₁·P₂`, the same arithmetic as the two-primary form.
pub fn functional_spline(p: &[f32], b: &[f32], lambda: f32) -> f32 {
    let bounds = b.iter().fold(lambda, |acc, &x| acc * (x * x));
    let primaries = p.iter().fold(1.0 - lambda, |acc, &x| acc * -x);
    bounds - primaries
}

/// What keeps the region outside the intersection outside, inside the bounds: `G` can be
/// negative wherever an even number of primaries are positive, so the result is at least the
/// second-largest primary, positive wherever two or more are. For two primaries that is
/// `min(P₁, P₂)`.
pub fn second_largest(p: &[f32]) -> f32 {
    let (mut first, mut second) = (f32::NEG_INFINITY, f32::NEG_INFINITY);
    for &x in p {
        if x > first {
            second = first;
            first = x;
        } else if x > second {
            second = x;
        }
    }
    second
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_two_primary_spline_keeps_its_values() {
        // The form with one bound per primary, as it was written before n and m were free.
        for (p, b, l) in [
            ([0.3f32, -1.2], [0.9f32, -0.4], 0.5f32),
            ([-0.71, -0.05], [1.7, 0.33], 0.2),
        ] {
            let before = l * (b[0] * b[0]) * (b[1] * b[1]) - (1.0 - l) * p[0] * p[1];
            assert_eq!(functional_spline(&p, &b, l).to_bits(), before.to_bits());
        }
        assert_eq!(second_largest(&[0.2, -0.4]), -0.4);
    }

    #[test]
    fn a_vertex_spline_of_three_planes_is_negative_inside_and_meets_them_on_the_bound() {
        // The octant x, y, z ≤ 0 with one bound, the plane x + y + z = −1 (negative on the
        // vertex's side).
        let b = |x: f32, y: f32, z: f32| -(x + y + z) - 1.0;
        let g = |x: f32, y: f32, z: f32| functional_spline(&[x, y, z], &[b(x, y, z)], 0.5);
        // Deep inside the octant, and the vertex cut off.
        assert!(g(-0.4, -0.4, -0.4) < 0.0);
        assert!(g(-0.05, -0.05, -0.05) > 0.0);
        // On the bound the product of primaries vanishes only on a primary: the zero set
        // meets each face where the bound does, e.g. (0, −0.5, −0.5).
        assert!(g(0.0, -0.5, -0.5).abs() < 1e-7);
        // Along the body diagonal the zero is at λ(3s − 1)² = (1 − λ)s³ with x = y = z = −s:
        // checked against an independent bisection of that cubic.
        let cubic = |s: f64| 0.5 * (1.0 - 3.0 * s).powi(2) - 0.5 * s.powi(3);
        let (mut lo, mut hi) = (0.05f64, 0.3f64);
        assert!(cubic(lo) > 0.0 && cubic(hi) < 0.0);
        for _ in 0..60 {
            let m = 0.5 * (lo + hi);
            if cubic(m) > 0.0 {
                lo = m
            } else {
                hi = m
            }
        }
        let s = lo as f32;
        assert!(
            g(-s + 1e-3, -s + 1e-3, -s + 1e-3) > 0.0 && g(-s - 1e-3, -s - 1e-3, -s - 1e-3) < 0.0
        );
    }

    #[test]
    fn splines_without_an_edge_or_a_bound_are_refused() {
        assert!(check_spline(2, 2).is_ok() && check_spline(3, 1).is_ok());
        let e = check_spline(1, 1).unwrap_err().to_string();
        assert!(
            e.contains("1 primaries and 1 bounds") && !e.contains("--"),
            "{e}"
        );
        assert!(check_spline(2, 0).is_err());
    }

    #[test]
    fn the_clamp_is_positive_where_two_primaries_are() {
        assert!(second_largest(&[0.1, 0.3, -0.5]) > 0.0);
        assert!(second_largest(&[0.1, -0.3, -0.5]) < 0.0);
        assert!(second_largest(&[-0.1, -0.3, -0.5]) < 0.0);
    }
}
