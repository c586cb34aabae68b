//! Moving a vertex onto the zero set of the continuous field.

use glam::Vec3;

use crate::field::Field;

/// Newton steps towards `field == iso` along the gradient from `p`, each result kept inside the
/// box `lo..hi`. Stops early on a vanishing or non-finite gradient, keeping the last good point.
pub(crate) fn project(
    field: &dyn Field,
    mut p: Vec3,
    iso: f32,
    lo: Vec3,
    hi: Vec3,
    steps: usize,
) -> Vec3 {
    for _ in 0..steps {
        let (value, grad) = field.value_gradient(p);
        let g2 = grad.length_squared();
        let d = value - iso;
        if d == 0.0 || g2 <= 0.0 || !d.is_finite() || !g2.is_finite() {
            break;
        }
        let next = (p - grad * (d / g2)).clamp(lo, hi);
        if !next.is_finite() {
            break;
        }
        p = next;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lands_on_a_sphere_and_respects_the_box() {
        let f = |p: Vec3| (p.length() - 1.0, p.normalize_or_zero());
        let p = project(&f, Vec3::new(0.6, 0.5, 0.4), 0.0, Vec3::ZERO, Vec3::ONE, 4);
        assert!((p.length() - 1.0).abs() < 1e-6);
        let q = project(
            &f,
            Vec3::new(0.1, 0.1, 0.1),
            0.0,
            Vec3::ZERO,
            Vec3::splat(0.2),
            4,
        );
        assert!(q.max_element() <= 0.2);
    }
}
