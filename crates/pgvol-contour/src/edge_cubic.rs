//! A cubic B-spline field along an edge of its own coefficient grid, read directly from the
//! coefficients.
//!
//! On such an edge the two cross-axis coordinates sit on nodes, where the cubic B-spline has
//! the weights (1/6, 2/3, 1/6), and along the edge the field is one cubic polynomial. Its four
//! B-spline control values along the edge come from 4 × 3 × 3 coefficients, a quarter of the
//! reads of two general evaluations, and give the field anywhere on the edge.

use glam::{Vec3, Vec4};
use pgvol_field::{Basis, CoefficientVolume};

use crate::cube::plane_axes;
use crate::place::onto_edge;
use crate::root::root_from_thirds;

/// Weights of the cubic B-spline at a node, for the coefficients at offsets -1, 0, 1.
const NODE_WEIGHTS: [f32; 3] = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0];

/// The 4 × 3 × 3 coefficients around a grid edge: `coeffs` starts at the lowest, and
/// `strides` step along the edge's axis and its two plane axes.
struct EdgeStencil {
    coeffs: [f32; 36],
    strides: [usize; 3],
    axis: usize,
}

impl EdgeStencil {
    /// The coefficients at plane offsets `(du, dv)` and offsets -1..=2 along the edge.
    #[inline]
    fn line(&self, du: usize, dv: usize) -> Vec4 {
        let [sa, su, sv] = self.strides;
        let at = du * su + dv * sv;
        Vec4::from_array(std::array::from_fn(|m| self.coeffs[at + m * sa]))
    }

    /// Control values of the field along the edge (lanes: offsets -1..=2): per position, the
    /// node weights across, summed over the u offsets first, then over v.
    #[inline]
    fn value_control(&self) -> Vec4 {
        let mut sum = Vec4::ZERO;
        for (dv, &wv) in NODE_WEIGHTS.iter().enumerate() {
            let across = NODE_WEIGHTS[0] * self.line(0, dv)
                + NODE_WEIGHTS[1] * self.line(1, dv)
                + NODE_WEIGHTS[2] * self.line(2, dv);
            sum += wv * across;
        }
        sum
    }

    /// [`Self::value_control`] and the control values of the slopes across the edge, along its
    /// first and second plane axes, from one read of each line; each sum is added in the
    /// order of its own loop, so the floats are those of separate passes.
    #[inline]
    fn value_and_slope_controls(&self) -> (Vec4, [Vec4; 2]) {
        let mut value = Vec4::ZERO;
        let mut slope = [Vec4::ZERO; 2];
        for (dv, &wv) in NODE_WEIGHTS.iter().enumerate() {
            let c = [0, 1, 2].map(|du| self.line(du, dv));
            let across = NODE_WEIGHTS[0] * c[0] + NODE_WEIGHTS[1] * c[1] + NODE_WEIGHTS[2] * c[2];
            value += wv * across;
            for (du, &c) in c.iter().enumerate() {
                slope[0] += (NODE_SLOPES[du] * wv) * c;
                slope[1] += (NODE_WEIGHTS[du] * NODE_SLOPES[dv]) * c;
            }
        }
        (value, slope)
    }
}

/// The stencil of the grid edge from `a` to `b` when `volume` is a cubic B-spline, `a` and `b`
/// are adjacent nodes of its grid and the stencil lies inside the grid.
fn edge_stencil(volume: &CoefficientVolume, a: Vec3, b: Vec3) -> Option<EdgeStencil> {
    if volume.basis != Basis::Bspline3 {
        return None;
    }
    let g = &volume.grid;
    let (ua, ub) = (g.to_grid(a), g.to_grid(b));
    let (na, nb) = (ua.round(), ub.round());
    // Both ends must be nodes (to float rounding) and differ along one axis by one node.
    if (ua - na).abs().max_element() > 1e-3 || (ub - nb).abs().max_element() > 1e-3 {
        return None;
    }
    let step = nb - na;
    let axis = (0..3).find(|&i| step[i] == 1.0)?;
    if step.abs().element_sum() != 1.0 {
        return None;
    }
    let n = na.to_array();
    let dims = g.dims.map(|d| d as f32);
    // Coefficients from n - 1 to n + 2 along the axis and n ± 1 across must exist.
    let fits = (0..3).all(|i| {
        let hi = if i == axis { 2.0 } else { 1.0 };
        n[i] >= 1.0 && n[i] + hi <= dims[i] - 1.0
    });
    if !fits {
        return None;
    }
    let n = n.map(|x| x as usize);
    let (u, v) = plane_axes(axis);
    // The 4 x 3 x 3 block from the lowest coefficient of the stencil, x fastest.
    let mut size = [3; 3];
    size[axis] = 4;
    let all = [1, size[0], size[0] * size[1]];
    let strides = [all[axis], all[u], all[v]];
    let mut coeffs = [0.0f32; 36];
    volume.coeffs.gather(n.map(|c| c - 1), size, &mut coeffs);
    Some(EdgeStencil {
        coeffs,
        strides,
        axis,
    })
}

/// The field of `volume` at the third points of the grid edge from `a` to `b`, when `volume` is
/// a cubic B-spline, `a` and `b` are adjacent nodes of its grid, and the edge's stencil lies
/// inside the grid; `None` otherwise (the caller then evaluates the field in general).
pub(crate) fn thirds_on_grid_edge(
    volume: &CoefficientVolume,
    a: Vec3,
    b: Vec3,
) -> Option<[f32; 2]> {
    let control = edge_stencil(volume, a, b)?.value_control().to_array();
    Some([1.0 / 3.0, 2.0 / 3.0].map(|t| along_edge(control, t)))
}

/// Derivative weights of the cubic B-spline at a node, for the coefficients at offsets -1, 0, 1.
const NODE_SLOPES: [f32; 3] = [-0.5, 0.0, 0.5];

/// The crossing of `iso` on the grid edge from `a` (value `va`) to `b` (value `vb`), placed as
/// [`thirds_on_grid_edge`] and `root_from_thirds` place it and put onto the edge, with the unit
/// gradient there (zero where it vanishes), all from one read of the edge's stencil; `None`
/// where [`thirds_on_grid_edge`] declines or a node value is not finite.
pub(crate) fn crossing_on_grid_edge(
    volume: &CoefficientVolume,
    a: Vec3,
    va: f32,
    b: Vec3,
    vb: f32,
    iso: f32,
) -> Option<(Vec3, Vec3)> {
    if !(va.is_finite() && vb.is_finite()) {
        return None;
    }
    let stencil = edge_stencil(volume, a, b)?;
    let axis = stencil.axis;
    let (value, [slope_u, slope_v]) = stencil.value_and_slope_controls();
    let value = value.to_array();
    let thirds = [1.0 / 3.0, 2.0 / 3.0].map(|t| along_edge(value, t));
    let p = onto_edge(a, b, axis, root_from_thirds(a, va, b, vb, thirds, iso));
    let t = (p[axis] - a[axis]) / (b[axis] - a[axis]);
    let s = 1.0 - t;
    let slopes = Vec4::new(
        -0.5 * s * s,
        1.5 * t * t - 2.0 * t,
        -(1.5 * s * s - 2.0 * s),
        0.5 * t * t,
    );
    let (u, v) = plane_axes(axis);
    let mut grad = Vec3::ZERO;
    grad[axis] = slopes.dot(Vec4::from_array(value));
    grad[u] = along_edge(slope_u.to_array(), t);
    grad[v] = along_edge(slope_v.to_array(), t);
    // Only the direction is wanted, so the spacing does not enter.
    Some((p, grad.normalize_or_zero()))
}

/// The cubic B-spline with control values `c` at offsets -1, 0, 1, 2, at `t` in [0, 1].
#[inline]
fn along_edge(c: [f32; 4], t: f32) -> f32 {
    let (w, _) = crate::cubic_eval::weights(t);
    w[0] * c[0] + w[1] * c[1] + w[2] * c[2] + w[3] * c[3]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_general_evaluation_inside_and_declines_elsewhere() {
        let volume = crate::cubic_eval::rough_volume();
        let grid = volume.grid;
        for (n, axis) in [
            ([3, 4, 5], 0),
            ([1, 1, 1], 1),
            ([5, 2, 6], 2),
            ([8, 7, 6], 0),
        ] {
            let a = grid.point(n[0], n[1], n[2]);
            let mut m = n;
            m[axis] += 1;
            let b = grid.point(m[0], m[1], m[2]);
            let thirds = thirds_on_grid_edge(&volume, a, b).unwrap();
            for (t, got) in [1.0 / 3.0, 2.0 / 3.0].into_iter().zip(thirds) {
                let want = volume.value(a + (b - a) * t);
                assert!((got - want).abs() < 1e-5, "{n:?} {axis}: {got} vs {want}");
            }
        }
        let mut checked = 0;
        for (n, axis, t) in [
            ([3, 4, 5], 0, 0.3),
            ([2, 1, 3], 1, 0.8),
            ([5, 2, 6], 2, 0.55),
        ] {
            // An iso level crossed at `t` along the edge, and node values on either side.
            let a = grid.point(n[0], n[1], n[2]);
            let mut m = n;
            m[axis] += 1;
            let b = grid.point(m[0], m[1], m[2]);
            let iso = volume.value(a + (b - a) * t);
            let (va, vb) = (volume.value(a), volume.value(b));
            if (va < iso) == (vb < iso) {
                continue;
            }
            let (p, normal) = crossing_on_grid_edge(&volume, a, va, b, vb, iso).unwrap();
            assert!((volume.value(p) - iso).abs() < 1e-4, "{n:?} {axis}: {p}");
            let want = volume.eval(p).1.normalize();
            assert!((normal - want).length() < 1e-4, "{normal} vs {want}");
            checked += 1;
        }
        assert!(checked >= 2, "{checked}");
        let (a, b) = (grid.point(3, 4, 5), grid.point(4, 4, 5));
        assert!(crossing_on_grid_edge(&volume, a, f32::NAN, b, 1.0, 0.0).is_none());
        let corner = grid.point(0, 0, 0);
        assert!(thirds_on_grid_edge(&volume, corner, grid.point(1, 0, 0)).is_none());
        let a = grid.point(3, 4, 5);
        assert!(thirds_on_grid_edge(&volume, a, a + Vec3::new(0.05, 0.0, 0.0)).is_none());
        assert!(thirds_on_grid_edge(&volume, a, grid.point(4, 5, 5)).is_none());
    }
}
