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

/// The crossing of `iso` between `a` and `b` on the cubic that interpolates the field at the
/// two nodes (`va`, `vb`) and at the edge's third points, which costs two field evaluations.
///
/// Along a grid edge of its own grid a cubic B-spline field *is* a cubic polynomial, so this is
/// its exact crossing at a third of the cost of [`edge_root`]; for other smooth fields the
/// interpolation error shrinks with the fourth power of the edge length. The root is found by
/// regula falsi on the cubic, inside a third of the edge where the four values change sign.
/// Non-finite values fall back to [`edge_root`].
pub(crate) fn cubic_edge_root(
    field: &dyn Field,
    a: Vec3,
    va: f32,
    b: Vec3,
    vb: f32,
    iso: f32,
) -> Vec3 {
    let d = b - a;
    let thirds = [
        field.value(a + d * (1.0 / 3.0)),
        field.value(a + d * (2.0 / 3.0)),
    ];
    if !(thirds.iter().all(|v| v.is_finite()) && va.is_finite() && vb.is_finite()) {
        return edge_root(field, a, va, b, vb, iso);
    }
    root_from_thirds(a, va, b, vb, thirds, iso)
}

/// The crossing of `iso` on the cubic through the finite values `va`, `thirds[0]`, `thirds[1]`,
/// `vb` at a, a + (b - a) / 3, a + 2 (b - a) / 3, b; `va` and `vb` straddle iso.
pub(crate) fn root_from_thirds(
    a: Vec3,
    va: f32,
    b: Vec3,
    vb: f32,
    thirds: [f32; 2],
    iso: f32,
) -> Vec3 {
    let d = b - a;
    let f = [va - iso, thirds[0] - iso, thirds[1] - iso, vb - iso];
    // The first third whose ends differ in sign; the ends of the edge do, so one exists.
    let inside = f[0] < 0.0;
    let third = (0..3).find(|&q| (f[q + 1] < 0.0) != inside).unwrap_or(2);
    let cubic = Cubic::through(f);
    let (mut t0, mut t1) = (third as f32 / 3.0, (third + 1) as f32 / 3.0);
    let (mut f0, mut f1) = (f[third], f[third + 1]);
    let mut t = t0 - f0 * (t1 - t0) / (f1 - f0);
    let mut side = 0i8;
    for _ in 0..STEPS {
        if !t.is_finite() {
            t = 0.5 * (t0 + t1);
        }
        let v = cubic.at(t);
        if v == 0.0 || t1 - t0 < 1e-7 {
            break;
        }
        if (v < 0.0) == (f0 < 0.0) {
            (t0, f0) = (t, v);
            if side == 1 {
                f1 *= 0.5;
            }
            side = 1;
        } else {
            (t1, f1) = (t, v);
            if side == -1 {
                f0 *= 0.5;
            }
            side = -1;
        }
        t = t0 - f0 * (t1 - t0) / (f1 - f0);
    }
    a + d * t.clamp(0.0, 1.0)
}

/// The cubic through the values at t = 0, 1/3, 2/3, 1, in Newton form.
struct Cubic {
    c: [f32; 4],
}

impl Cubic {
    fn through(f: [f32; 4]) -> Self {
        // Divided differences on the nodes 0, 1/3, 2/3, 1 (spacing 1/3).
        let d1 = [
            3.0 * (f[1] - f[0]),
            3.0 * (f[2] - f[1]),
            3.0 * (f[3] - f[2]),
        ];
        let d2 = [1.5 * (d1[1] - d1[0]), 1.5 * (d1[2] - d1[1])];
        let d3 = d2[1] - d2[0];
        Self {
            c: [f[0], d1[0], d2[0], d3],
        }
    }

    #[inline]
    fn at(&self, t: f32) -> f32 {
        let [c0, c1, c2, c3] = self.c;
        c0 + t * (c1 + (t - 1.0 / 3.0) * (c2 + (t - 2.0 / 3.0) * c3))
    }
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
    fn cubic_root_is_exact_for_cubic_fields() {
        // A cubic along x with one root at x = 0.3 in [0, 1], plus terms that are constant
        // along the edge.
        let f = |p: Vec3| {
            let x = p.x;
            let v = (x - 0.3) * (x * x + 0.5) + 0.2 * p.y;
            (v, Vec3::new(3.0 * x * x - 0.6 * x + 0.5, 0.2, 0.0))
        };
        let (a, b) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0));
        let p = cubic_edge_root(&f, a, f(a).0, b, f(b).0, 0.0);
        assert!((p.x - 0.3).abs() < 1e-6, "{}", p.x);
    }

    #[test]
    fn cubic_root_is_close_on_a_curved_field() {
        let f = |p: Vec3| (p.length() - 0.7, p.normalize_or_zero());
        let (a, b) = (Vec3::new(0.6, 0.3, 0.0), Vec3::new(0.7, 0.3, 0.0));
        let p = cubic_edge_root(&f, a, f(a).0, b, f(b).0, 0.0);
        // A 1e-4 fraction of the edge; linear interpolation is off by about 3e-2 of it here.
        assert!((p.length() - 0.7).abs() < 1e-5, "{}", p.length());
        let linear = crate::place::lerp_crossing(a, f(a).0, b, f(b).0, 0.0);
        assert!((linear.length() - 0.7).abs() > 10.0 * (p.length() - 0.7).abs());
    }

    #[test]
    fn bisects_when_a_sample_is_nan() {
        let f = |p: Vec3| (if p.x < 0.25 { -1.0 } else { f32::NAN }, Vec3::X);
        let p = edge_root(&f, Vec3::ZERO, -1.0, Vec3::X, f32::NAN, 0.0);
        assert!((p.x - 0.25).abs() < 1e-3, "{}", p.x);
    }
}
