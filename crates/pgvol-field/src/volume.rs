//! The coefficient volume: a grid, a basis and one coefficient per node.

use glam::{Mat3, Vec3};
use rayon::prelude::*;

use crate::basis::Basis;
use crate::stencil::{self, GRADIENT, HESSIAN, VALUE};
use pgvol_core::sparse::brick_offset;
use pgvol_core::{Background, Grid, SparseGrid};

/// Why a coefficient volume could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FieldError {
    #[error("{got} values given for a grid of {want} nodes")]
    SizeMismatch { got: usize, want: usize },
    #[error("the grid needs at least 2 nodes per axis, got {0:?}")]
    GridTooSmall([usize; 3]),
    #[error("value {index} is not finite")]
    NonFinite { index: usize },
    #[error("invalid basis: {0}")]
    BadBasis(String),
    #[error("invalid fit: {0}")]
    BadFit(String),
    #[error("coefficients for {got:?} nodes given for a grid of {want:?}")]
    DimsMismatch { got: [usize; 3], want: [usize; 3] },
}

/// A smooth field `f(x) = Σ_j c_j B((x − g_j) / h)` over a grid. The coefficients are sparse:
/// bricks near the surface are stored, the others hold their side's clamp value.
#[derive(Clone, Debug, PartialEq)]
pub struct CoefficientVolume {
    pub grid: Grid,
    pub basis: Basis,
    pub coeffs: SparseGrid,
}

/// Checks what every constructor needs: a valid basis, at least 2 nodes per axis, one finite
/// value per node.
pub(crate) fn check_inputs(grid: &Grid, basis: Basis, values: &[f32]) -> Result<(), FieldError> {
    basis.validate().map_err(FieldError::BadBasis)?;
    if grid.dims.iter().any(|&n| n < 2) {
        return Err(FieldError::GridTooSmall(grid.dims));
    }
    if values.len() != grid.len() {
        return Err(FieldError::SizeMismatch {
            got: values.len(),
            want: grid.len(),
        });
    }
    if let Some(index) = values.iter().position(|c| !c.is_finite()) {
        return Err(FieldError::NonFinite { index });
    }
    Ok(())
}

/// What every sparse constructor needs: a valid basis, at least 2 nodes per axis, values on
/// `grid`'s nodes, a finite background and finite stored values at the grid's nodes (the error
/// names the first bad node's flat index).
pub fn check_sparse(grid: &Grid, basis: Basis, values: &SparseGrid) -> Result<(), FieldError> {
    basis.validate().map_err(FieldError::BadBasis)?;
    if grid.dims.iter().any(|&n| n < 2) {
        return Err(FieldError::GridTooSmall(grid.dims));
    }
    if values.dims() != grid.dims {
        return Err(FieldError::DimsMismatch {
            got: values.dims(),
            want: grid.dims,
        });
    }
    let bg = values.background();
    if !(bg.inside.is_finite() && bg.outside.is_finite()) {
        return Err(FieldError::NonFinite { index: 0 });
    }
    // The first bad brick in storage order, as a loop over them would find it.
    let bad = values.stored_par().find_map_first(|(b, brick)| {
        let (lo, n) = values.brick_extent(b);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    if !brick[brick_offset([i, j, k])].is_finite() {
                        return Some(grid.index(lo[0] + i, lo[1] + j, lo[2] + k));
                    }
                }
            }
        }
        None
    });
    match bad {
        Some(index) => Err(FieldError::NonFinite { index }),
        None => Ok(()),
    }
}

impl CoefficientVolume {
    /// Wraps existing coefficients (one per node, x fastest), checking the basis, their count
    /// and finiteness; every brick is stored.
    pub fn new(grid: Grid, basis: Basis, coeffs: Vec<f32>) -> Result<Self, FieldError> {
        check_inputs(&grid, basis, &coeffs)?;
        let coeffs = SparseGrid::from_dense(grid.dims, &coeffs, Background::clamp(0.0));
        Ok(CoefficientVolume {
            grid,
            basis,
            coeffs,
        })
    }

    /// Wraps sparse coefficients, checking them as [`check_sparse`] does.
    pub fn from_sparse(grid: Grid, basis: Basis, coeffs: SparseGrid) -> Result<Self, FieldError> {
        check_sparse(&grid, basis, &coeffs)?;
        Ok(CoefficientVolume {
            grid,
            basis,
            coeffs,
        })
    }

    /// Every coefficient, x fastest: the dense export.
    pub fn dense_coeffs(&self) -> Vec<f32> {
        self.coeffs.to_dense()
    }

    /// Value, gradient and Hessian (Hessian left zero below `ORDER`) at `p`. Points outside the
    /// grid box take the value at the nearest box point plus their distance to it, so the field
    /// stays continuous and grows outward.
    #[inline]
    fn jet<const ORDER: u8>(&self, p: Vec3) -> (f32, Vec3, Mat3) {
        let g = &self.grid;
        let q = p.clamp(g.origin, g.max_corner());
        let outside = p.distance(q);
        let u = g.to_grid(q);
        let mut value = 0.0f32;
        let mut grad = Vec3::ZERO;
        let mut hess = Mat3::ZERO;
        stencil::visit_nodes::<ORDER>(self.basis, g.dims, u, |n, jet| {
            let c = self.coeffs.get(n);
            value += c * jet.value;
            if ORDER >= GRADIENT {
                grad += c * jet.gradient;
            }
            if ORDER >= HESSIAN {
                hess += jet.hessian * c;
            }
        });
        let h = g.spacing;
        let (grad, hess) = (grad / h, hess * (1.0 / (h * h)));
        if outside > 0.0 {
            let dir = (p - q) / outside;
            let grad = if grad.dot(dir) < 1.0 {
                grad + dir
            } else {
                grad
            };
            (value + outside, grad, hess)
        } else {
            (value, grad, hess)
        }
    }

    /// Field value and gradient at `p`. Points outside the grid box take the value at the
    /// nearest point of the box plus their distance to it, so the field stays continuous and
    /// grows outward.
    pub fn eval(&self, p: Vec3) -> (f32, Vec3) {
        let (v, g, _) = self.jet::<GRADIENT>(p);
        (v, g)
    }

    /// Value, gradient and Hessian at `p` (outside the box: as [`Self::eval`], with the
    /// Hessian of the nearest box point).
    pub fn eval_hessian(&self, p: Vec3) -> (f32, Vec3, Mat3) {
        self.jet::<HESSIAN>(p)
    }

    /// Values, gradients and Hessians at many points, in parallel.
    pub fn eval_hessian_many(&self, points: &[Vec3]) -> Vec<(f32, Vec3, Mat3)> {
        points.par_iter().map(|&p| self.eval_hessian(p)).collect()
    }

    /// Field value only.
    #[inline]
    pub fn value(&self, p: Vec3) -> f32 {
        self.jet::<VALUE>(p).0
    }

    /// Values and gradients at many points, in parallel.
    pub fn eval_many(&self, points: &[Vec3]) -> Vec<(f32, Vec3)> {
        points.par_iter().map(|&p| self.eval(p)).collect()
    }

    /// Values only at many points, in parallel.
    pub fn values_many(&self, points: &[Vec3]) -> Vec<f32> {
        points.par_iter().map(|&p| self.value(p)).collect()
    }

    /// The field sampled at every node of `grid` (x fastest), in parallel over z-planes.
    pub fn sample(&self, grid: &Grid) -> Vec<f32> {
        let [nx, ny, _] = grid.dims;
        let mut out = vec![0.0f32; grid.len()];
        out.par_chunks_mut(nx * ny)
            .enumerate()
            .for_each(|(k, plane)| {
                for j in 0..ny {
                    for i in 0..nx {
                        plane[i + nx * j] = self.value(grid.point(i, j, k));
                    }
                }
            });
        out
    }

    /// The zero of the field on the segment from `a` (value `va`) to `b` (value `vb`), where the
    /// values have opposite signs relative to `iso`: regula falsi with the Illinois modification,
    /// a few steps, falling back to the best bracket end so the result stays on the segment.
    pub fn root_on_segment(&self, a: Vec3, va: f32, b: Vec3, vb: f32, iso: f32) -> Vec3 {
        let (mut t0, mut f0) = (0.0f32, va - iso);
        let (mut t1, mut f1) = (1.0f32, vb - iso);
        if f0 == f1 || (f0 < 0.0) == (f1 < 0.0) {
            return a + (b - a) * 0.5;
        }
        let mut side = 0i8;
        let mut t = t0 - f0 * (t1 - t0) / (f1 - f0);
        for _ in 0..8 {
            t = t0 - f0 * (t1 - t0) / (f1 - f0);
            let f = self.value(a + (b - a) * t) - iso;
            if f == 0.0 || (t1 - t0).abs() < 1e-6 {
                break;
            }
            if (f < 0.0) == (f1 < 0.0) {
                t1 = t;
                f1 = f;
                if side == -1 {
                    f0 *= 0.5;
                }
                side = -1;
            } else {
                t0 = t;
                f0 = f;
                if side == 1 {
                    f1 *= 0.5;
                }
                side = 1;
            }
        }
        a + (b - a) * t.clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> Grid {
        Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), n).unwrap()
    }

    fn sampled(grid: &Grid, f: impl Fn(Vec3) -> f32) -> Vec<f32> {
        let mut v = Vec::with_capacity(grid.len());
        for k in 0..grid.dims[2] {
            for j in 0..grid.dims[1] {
                for i in 0..grid.dims[0] {
                    v.push(f(grid.point(i, j, k)));
                }
            }
        }
        v
    }

    #[test]
    fn both_bases_interpolate_the_samples_at_nodes() {
        let g = grid(12);
        let sphere = |p: Vec3| p.length() - 0.7;
        for basis in [Basis::Trilinear, Basis::Bspline3] {
            let vol = CoefficientVolume::interpolate(g, basis, sampled(&g, sphere)).unwrap();
            for (i, j, k) in [(0, 0, 0), (3, 4, 5), (11, 11, 11), (6, 0, 9)] {
                let p = g.point(i, j, k);
                assert!((vol.value(p) - sphere(p)).abs() < 1e-4, "{basis:?} at {p}");
            }
        }
    }

    #[test]
    fn bspline_is_much_more_accurate_between_nodes() {
        let g = grid(24);
        let sphere = |p: Vec3| p.length() - 0.6;
        let err = |basis| {
            let vol = CoefficientVolume::interpolate(g, basis, sampled(&g, sphere)).unwrap();
            let mut worst = 0.0f32;
            for n in 0..2000 {
                let d = Vec3::new(
                    (n as f32 * 0.618).sin(),
                    (n as f32 * 1.3).cos(),
                    (n as f32 * 0.77).sin(),
                )
                .normalize();
                let p = d * 0.6;
                worst = worst.max(vol.value(p).abs());
            }
            worst
        };
        let (tri, bs) = (err(Basis::Trilinear), err(Basis::Bspline3));
        assert!(bs * 5.0 < tri, "bspline {bs} trilinear {tri}");
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let g = grid(16);
        let f = |p: Vec3| (p.x * 2.0).sin() + p.y * p.z - 0.3 * p.z;
        for basis in [Basis::Trilinear, Basis::Bspline3] {
            let vol = CoefficientVolume::interpolate(g, basis, sampled(&g, f)).unwrap();
            for p in [Vec3::new(0.13, -0.21, 0.37), Vec3::new(-0.5, 0.44, 0.02)] {
                let (_, grad) = vol.eval(p);
                let e = 1e-3;
                let fd = Vec3::new(
                    vol.value(p + Vec3::X * e) - vol.value(p - Vec3::X * e),
                    vol.value(p + Vec3::Y * e) - vol.value(p - Vec3::Y * e),
                    vol.value(p + Vec3::Z * e) - vol.value(p - Vec3::Z * e),
                ) / (2.0 * e);
                assert!((grad - fd).length() < 2e-2, "{basis:?} {p}: {grad} vs {fd}");
            }
        }
    }

    #[test]
    fn root_finding_lands_on_the_zero_set() {
        let g = grid(20);
        let sphere = |p: Vec3| p.length() - 0.55;
        let vol = CoefficientVolume::interpolate(g, Basis::Bspline3, sampled(&g, sphere)).unwrap();
        let (a, b) = (Vec3::new(0.1, 0.2, 0.0), Vec3::new(0.8, 0.3, 0.1));
        let r = vol.root_on_segment(a, vol.value(a), b, vol.value(b), 0.0);
        assert!(vol.value(r).abs() < 1e-4);
        assert!((r.length() - 0.55).abs() < 2e-3);
    }

    #[test]
    fn bad_inputs_are_refused() {
        let g = grid(4);
        assert!(CoefficientVolume::new(g, Basis::Bspline3, vec![0.0; 3]).is_err());
        let mut v = vec![0.0; 64];
        v[5] = f32::NAN;
        assert_eq!(
            CoefficientVolume::interpolate(g, Basis::Bspline3, v).err(),
            Some(FieldError::NonFinite { index: 5 })
        );
    }

    #[test]
    fn outside_the_box_the_field_grows() {
        let g = grid(8);
        let vol =
            CoefficientVolume::interpolate(g, Basis::Bspline3, sampled(&g, |p| p.length() - 0.5))
                .unwrap();
        let edge = vol.value(g.max_corner());
        assert!(vol.value(g.max_corner() + Vec3::splat(1.0)) > edge + 1.0);
    }
}
