//! Value and gradient of a cubic B-spline volume at any point well inside its grid.
//!
//! The general evaluation of `pgvol-field` serves every basis: it computes a full jet per node
//! of the 4³ stencil and mirrors indices at the border. Dual contouring evaluates the field a
//! few times per vertex (projection onto the zero set, tangent planes near features), so there
//! the cubic B-spline gets its own path: the separable weights once per axis, then one pass
//! over the 16 rows of 4 coefficients, each row a vector.

use glam::{Vec3, Vec4};
use pgvol_field::{Basis, CoefficientVolume};

/// Value and gradient of `volume` at `p` when `volume` is a cubic B-spline and the 4³ stencil
/// of `p` lies inside the grid without mirroring (at least one node from the border); `None`
/// otherwise, where the caller evaluates the field in general.
#[inline]
pub(crate) fn bspline3_value_gradient(volume: &CoefficientVolume, p: Vec3) -> Option<(f32, Vec3)> {
    if volume.basis != Basis::Bspline3 {
        return None;
    }
    let g = &volume.grid;
    let u = g.to_grid(p);
    let [nx, ny, nz] = g.dims;
    // The general path uses cell `floor(u)` with offsets -1..=2; all four nodes must exist.
    let fits = |x: f32, n: usize| x >= 1.0 && x < (n as f32 - 2.0);
    if !(fits(u.x, nx) && fits(u.y, ny) && fits(u.z, nz)) {
        return None;
    }
    // Truncation is the floor here (u >= 1), without a call into libm on baseline x86-64.
    let cell = Vec3::new(
        u.x as usize as f32,
        u.y as usize as f32,
        u.z as usize as f32,
    );
    let t = u - cell;
    let (wx, dx) = weights(t.x);
    let (wy, dy) = weights(t.y);
    let (wz, dz) = weights(t.z);
    let first = cell.to_array().map(|c| c as usize - 1);
    let mut stencil = [0.0f32; 64];
    volume.coeffs.gather(first, [4; 3], &mut stencil);
    let (nx, plane) = (4, 16);
    // Rows of four coefficients along x are weighted in y and z as whole vectors; the x
    // weights are applied once at the end.
    let (mut value, mut slope_y, mut slope_z) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
    for c in 0..4 {
        let (mut plane_value, mut plane_slope) = (Vec4::ZERO, Vec4::ZERO);
        for b in 0..4 {
            let row = Vec4::from_slice(&stencil[b * nx + c * plane..][..4]);
            plane_value += wy[b] * row;
            plane_slope += dy[b] * row;
        }
        value += wz[c] * plane_value;
        slope_y += wz[c] * plane_slope;
        slope_z += dz[c] * plane_value;
    }
    let (wx, dx) = (Vec4::from_array(wx), Vec4::from_array(dx));
    let gradient = Vec3::new(dx.dot(value), wx.dot(slope_y), wx.dot(slope_z));
    Some((wx.dot(value), gradient / g.spacing))
}

/// Weights and derivative weights of the nodes at offsets -1, 0, 1, 2 from the cell start, at
/// the fraction `t` of the cell.
#[inline]
pub(crate) fn weights(t: f32) -> ([f32; 4], [f32; 4]) {
    let s = 1.0 - t;
    let (t2, s2) = (t * t, s * s);
    let w = [
        s2 * s / 6.0,
        (3.0 * t2 * t - 6.0 * t2 + 4.0) / 6.0,
        (3.0 * s2 * s - 6.0 * s2 + 4.0) / 6.0,
        t2 * t / 6.0,
    ];
    let d = [-0.5 * s2, 1.5 * t2 - 2.0 * t, 2.0 * s - 1.5 * s2, 0.5 * t2];
    (w, d)
}

/// A cubic B-spline volume through pseudo-random samples on a small, off-origin grid, for
/// checking the fast paths against the general evaluation.
#[cfg(test)]
pub(crate) fn rough_volume() -> CoefficientVolume {
    let grid = pgvol_field::Grid {
        origin: Vec3::new(-1.0, -0.5, 0.25),
        spacing: 0.1,
        dims: [12, 10, 9],
        offset: Default::default(),
    };
    let samples: Vec<f32> = (0..grid.len())
        .map(|i| ((i * 7919) % 101) as f32 / 50.0 - 1.0)
        .collect();
    CoefficientVolume::interpolate(grid, Basis::Bspline3, samples).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_general_evaluation_inside_and_declines_near_the_border() {
        let volume = rough_volume();
        let grid = volume.grid;
        let mut checked = 0;
        for n in 0..500u32 {
            // A scatter of points over the whole box and a little beyond.
            let f = |k: u32| ((n * k) % 997) as f32 / 997.0 * 1.1 - 0.05;
            let size = grid.max_corner() - grid.origin;
            let p = grid.origin + size * Vec3::new(f(389), f(617), f(811));
            let want = volume.eval(p);
            let Some(got) = bspline3_value_gradient(&volume, p) else {
                let u = grid.to_grid(p);
                let near_border = (0..3).any(|i| u[i] < 1.0 || u[i] >= grid.dims[i] as f32 - 2.0);
                assert!(near_border, "{p} declined");
                continue;
            };
            checked += 1;
            assert!((got.0 - want.0).abs() < 1e-5, "{p}: {got:?} vs {want:?}");
            let scale = want.1.length().max(1.0);
            assert!(
                (got.1 - want.1).length() < 1e-4 * scale,
                "{p}: {got:?} vs {want:?}"
            );
        }
        assert!(checked > 100, "{checked}");
        let trilinear = CoefficientVolume {
            basis: Basis::Trilinear,
            ..volume.clone()
        };
        assert!(bspline3_value_gradient(&trilinear, grid.point(5, 5, 5)).is_none());
    }
}
