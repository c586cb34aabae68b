//! A cubic B-spline field along an edge of its own coefficient grid, read directly from the
//! coefficients.
//!
//! On such an edge the two cross-axis coordinates sit on nodes, where the cubic B-spline has
//! the weights (1/6, 2/3, 1/6), and along the edge the field is one cubic polynomial. Its four
//! B-spline control values along the edge come from 4 × 3 × 3 coefficients, a quarter of the
//! reads of two general evaluations, and give the field anywhere on the edge.

use glam::Vec3;
use pgvol_field::{Basis, CoefficientVolume};

use crate::cube::plane_axes;

/// Weights of the cubic B-spline at a node, for the coefficients at offsets -1, 0, 1.
const NODE_WEIGHTS: [f32; 3] = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0];

/// The field of `volume` at the third points of the grid edge from `a` to `b`, when `volume` is
/// a cubic B-spline, `a` and `b` are adjacent nodes of its grid, and the edge's stencil lies
/// inside the grid; `None` otherwise (the caller then evaluates the field in general).
pub(crate) fn thirds_on_grid_edge(
    volume: &CoefficientVolume,
    a: Vec3,
    b: Vec3,
) -> Option<[f32; 2]> {
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
    let [nx, ny, _] = g.dims;
    let strides = [1, nx, nx * ny];
    let (sa, su, sv) = (strides[axis], strides[u], strides[v]);
    // The lowest coefficient of the stencil, and the 4 x 3 x 3 block above it.
    let first = (n[0] + nx * (n[1] + ny * n[2])) - sa - su - sv;
    let stencil = volume
        .coeffs
        .get(first..=first + 3 * sa + 2 * su + 2 * sv)?;
    let mut control = [0.0f32; 4];
    for (m, c) in control.iter_mut().enumerate() {
        let mut sum = 0.0f32;
        for (dv, wv) in NODE_WEIGHTS.iter().enumerate() {
            let row = m * sa + dv * sv;
            let across = NODE_WEIGHTS[0] * stencil[row]
                + NODE_WEIGHTS[1] * stencil[row + su]
                + NODE_WEIGHTS[2] * stencil[row + 2 * su];
            sum += wv * across;
        }
        *c = sum;
    }
    Some([1.0 / 3.0, 2.0 / 3.0].map(|t| along_edge(control, t)))
}

/// Derivative weights of the cubic B-spline at a node, for the coefficients at offsets -1, 0, 1.
const NODE_SLOPES: [f32; 3] = [-0.5, 0.0, 0.5];

/// The gradient of `volume` at `p` when `volume` is a cubic B-spline and `p` lies on an edge of
/// its grid whose stencil is inside the grid (as edge crossings do); `None` otherwise. The same
/// 4 × 3 × 3 coefficients as [`thirds_on_grid_edge`] give the slope along the edge and, with
/// the node derivative weights (-1/2, 0, 1/2), the two slopes across it.
pub(crate) fn gradient_on_grid_edge(volume: &CoefficientVolume, p: Vec3) -> Option<Vec3> {
    if volume.basis != Basis::Bspline3 {
        return None;
    }
    let g = &volume.grid;
    let q = g.to_grid(p);
    let off = (q - q.round()).abs();
    // The coordinate furthest from a node runs along the edge; the others sit on nodes.
    let axis = (0..3).fold(0, |b, i| if off[i] > off[b] { i } else { b });
    let (u, v) = plane_axes(axis);
    if off[u] > 1e-3 || off[v] > 1e-3 {
        return None;
    }
    let mut n = q.round().to_array();
    n[axis] = q[axis].floor();
    let t = q[axis] - n[axis];
    let dims = g.dims.map(|d| d as f32);
    let fits = (0..3).all(|i| {
        let hi = if i == axis { 2.0 } else { 1.0 };
        n[i] >= 1.0 && n[i] + hi <= dims[i] - 1.0
    });
    if !fits {
        return None;
    }
    let n = n.map(|x| x as usize);
    let [nx, ny, _] = g.dims;
    let strides = [1, nx, nx * ny];
    let (sa, su, sv) = (strides[axis], strides[u], strides[v]);
    let first = (n[0] + nx * (n[1] + ny * n[2])) - sa - su - sv;
    let stencil = volume
        .coeffs
        .get(first..=first + 3 * sa + 2 * su + 2 * sv)?;
    // Per position along the edge: the value, u-slope and v-slope control values.
    let mut control = [[0.0f32; 4]; 3];
    for m in 0..4 {
        for dv in 0..3 {
            for du in 0..3 {
                let c = stencil[m * sa + du * su + dv * sv];
                control[0][m] += NODE_WEIGHTS[du] * NODE_WEIGHTS[dv] * c;
                control[1][m] += NODE_SLOPES[du] * NODE_WEIGHTS[dv] * c;
                control[2][m] += NODE_WEIGHTS[du] * NODE_SLOPES[dv] * c;
            }
        }
    }
    let s = 1.0 - t;
    let slopes = [
        -0.5 * s * s,
        1.5 * t * t - 2.0 * t,
        -(1.5 * s * s - 2.0 * s),
        0.5 * t * t,
    ];
    let dot = |w: [f32; 4], c: [f32; 4]| w[0] * c[0] + w[1] * c[1] + w[2] * c[2] + w[3] * c[3];
    let mut grad = Vec3::ZERO;
    grad[axis] = dot(slopes, control[0]);
    grad[u] = along_edge(control[1], t);
    grad[v] = along_edge(control[2], t);
    Some(grad / g.spacing)
}

/// The cubic B-spline with control values `c` at offsets -1, 0, 1, 2, at `t` in [0, 1].
#[inline]
fn along_edge(c: [f32; 4], t: f32) -> f32 {
    let s = 1.0 - t;
    let w = [
        s * s * s / 6.0,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
        (3.0 * s * s * s - 6.0 * s * s + 4.0) / 6.0,
        t * t * t / 6.0,
    ];
    w[0] * c[0] + w[1] * c[1] + w[2] * c[2] + w[3] * c[3]
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_field::Grid;

    #[test]
    fn matches_general_evaluation_inside_and_declines_elsewhere() {
        let grid = Grid {
            origin: Vec3::new(-1.0, -0.5, 0.25),
            spacing: 0.1,
            dims: [12, 10, 9],
        };
        let samples: Vec<f32> = (0..grid.len())
            .map(|i| ((i * 7919) % 101) as f32 / 50.0 - 1.0)
            .collect();
        let volume = CoefficientVolume::interpolate(grid, Basis::Bspline3, samples).unwrap();
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
        for (n, axis, t) in [
            ([3, 4, 5], 0, 0.3),
            ([2, 1, 3], 1, 0.8),
            ([5, 2, 6], 2, 0.55),
        ] {
            let mut p = grid.point(n[0], n[1], n[2]);
            p[axis] += t * grid.spacing;
            let got = gradient_on_grid_edge(&volume, p).unwrap();
            let want = volume.eval(p).1;
            assert!(
                (got - want).length() < 1e-3 * want.length().max(1.0),
                "{got} vs {want}"
            );
        }
        let corner = grid.point(0, 0, 0);
        assert!(thirds_on_grid_edge(&volume, corner, grid.point(1, 0, 0)).is_none());
        let a = grid.point(3, 4, 5);
        assert!(thirds_on_grid_edge(&volume, a, a + Vec3::new(0.05, 0.0, 0.0)).is_none());
        assert!(thirds_on_grid_edge(&volume, a, grid.point(4, 5, 5)).is_none());
    }
}
