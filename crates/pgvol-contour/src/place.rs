//! Placement of a surface vertex on a grid edge.

use glam::Vec3;

/// Fraction of the edge kept clear at each end, so crossings on edges meeting at a corner never
/// coincide even when a node value equals iso.
pub(crate) const END_MARGIN: f32 = 1e-4;

/// Puts `p` on the edge from `a` to `b` (which differ only along `axis`, `a` lower): projects it
/// onto the edge, keeps it `END_MARGIN` away from both ends, and falls back to the midpoint when
/// `p` is not finite. The result lies strictly between the ends even where the margin is below
/// float resolution.
pub(crate) fn onto_edge(a: Vec3, b: Vec3, axis: usize, p: Vec3) -> Vec3 {
    let (lo, hi) = (a[axis], b[axis]);
    let t = (p[axis] - lo) / (hi - lo);
    let t = if t.is_finite() { t } else { 0.5 };
    let t = t.clamp(END_MARGIN, 1.0 - END_MARGIN);
    let mut x = lo + t * (hi - lo);
    if x <= lo {
        x = step(lo, true);
    }
    if x >= hi {
        x = step(hi, false);
    }
    let mut out = a;
    out[axis] = x;
    out
}

/// The adjacent float above (`up`) or below a finite `x`.
fn step(x: f32, up: bool) -> f32 {
    if x == 0.0 {
        let tiny = f32::from_bits(1);
        return if up { tiny } else { -tiny };
    }
    let away_from_zero = (x > 0.0) == up;
    let bits = x.to_bits();
    f32::from_bits(if away_from_zero { bits + 1 } else { bits - 1 })
}

/// Linear interpolation of the iso crossing between two node values.
pub(crate) fn lerp_crossing(a: Vec3, va: f32, b: Vec3, vb: f32, iso: f32) -> Vec3 {
    a + (b - a) * ((iso - va) / (vb - va))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamps_projects_and_replaces_non_finite() {
        let (a, b) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 4.0, 3.0));
        let mid = onto_edge(a, b, 1, Vec3::new(9.0, 3.0, -9.0));
        assert_eq!(mid, Vec3::new(1.0, 3.0, 3.0));
        assert!(onto_edge(a, b, 1, a).y > 2.0);
        assert!(onto_edge(a, b, 1, Vec3::splat(100.0)).y < 4.0);
        assert_eq!(onto_edge(a, b, 1, Vec3::NAN), mid);
    }

    #[test]
    fn stays_strictly_inside_where_the_margin_underflows() {
        let (a, b) = (Vec3::new(1e6, 0.0, 0.0), Vec3::new(1e6 + 0.125, 0.0, 0.0));
        for p in [a, b] {
            let x = onto_edge(a, b, 0, p).x;
            assert!(x > a.x && x < b.x);
        }
        let (a, b) = (Vec3::new(-0.5, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.0));
        assert!(onto_edge(a, b, 0, b).x < 0.0);
    }

    #[test]
    fn interpolates_linearly() {
        let p = lerp_crossing(Vec3::ZERO, -1.0, Vec3::X, 3.0, 0.0);
        assert_eq!(p, Vec3::new(0.25, 0.0, 0.0));
    }
}
