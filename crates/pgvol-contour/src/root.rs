//! Crossing of the iso-surface on a grid edge, found on the continuous field.

use glam::Vec3;

use crate::field::Field;

/// Regula falsi steps; the Illinois variant converges superlinearly, so a few suffice for
/// f32 accuracy on smooth fields.
const STEPS: usize = 8;

/// The point between `a` and `b` where `field` crosses `iso`, bracketed by the node samples `va`
/// and `vb` (one inside, the other outside or NaN).
///
/// Regula falsi with the Illinois modification on the continuous field. Sample values that are
/// not finite give no slope to interpolate, so the search then bisects on the inside/outside
/// sign. A probe returning NaN stops the search at the best estimate so far.
pub(crate) fn edge_root(field: &dyn Field, a: Vec3, va: f32, b: Vec3, vb: f32, iso: f32) -> Vec3 {
    let (mut f0, mut f1) = (va - iso, vb - iso);
    let at = |t: f32| a + (b - a) * t;
    if !(f0.is_finite() && f1.is_finite()) {
        return bisect(field, a, b, iso, f0 < 0.0);
    }
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    let mut t = t0 - f0 * (t1 - t0) / (f1 - f0);
    let mut side = 0i8;
    for _ in 0..STEPS {
        let f = field.value(at(t)) - iso;
        if f == 0.0 || !f.is_finite() || t1 - t0 < 1e-6 {
            break;
        }
        // Keep the bracket; halve the value at an end that stays put twice running, which is
        // what stops plain regula falsi from crawling on convex pieces.
        if (f < 0.0) == (f0 < 0.0) {
            t0 = t;
            f0 = f;
            if side == 1 {
                f1 *= 0.5;
            }
            side = 1;
        } else {
            t1 = t;
            f1 = f;
            if side == -1 {
                f0 *= 0.5;
            }
            side = -1;
        }
        t = t0 - f0 * (t1 - t0) / (f1 - f0);
        if !t.is_finite() {
            t = 0.5 * (t0 + t1);
        }
    }
    at(t.clamp(0.0, 1.0))
}

fn bisect(field: &dyn Field, a: Vec3, b: Vec3, iso: f32, a_inside: bool) -> Vec3 {
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..12 {
        let m = 0.5 * (lo + hi);
        if (field.value(a + (b - a) * m) < iso) == a_inside {
            lo = m;
        } else {
            hi = m;
        }
    }
    a + (b - a) * (0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_curved_root_to_float_accuracy() {
        let f = |p: Vec3| (p.length() - 0.7, p.normalize_or_zero());
        let (a, b) = (Vec3::new(0.6, 0.3, 0.0), Vec3::new(0.7, 0.3, 0.0));
        let p = edge_root(&f, a, f(a).0, b, f(b).0, 0.0);
        assert!((p.length() - 0.7).abs() < 1e-6, "{}", p.length());
    }

    #[test]
    fn bisects_when_a_sample_is_nan() {
        let f = |p: Vec3| (if p.x < 0.25 { -1.0 } else { f32::NAN }, Vec3::X);
        let p = edge_root(&f, Vec3::ZERO, -1.0, Vec3::X, f32::NAN, 0.0);
        assert!((p.x - 0.25).abs() < 1e-3, "{}", p.x);
    }
}
