//! The field at every node of its own grid. A separable B-spline at the nodes is a 3-tap
//! convolution per axis (`[1, 4, 1]/6` cubic, `[1, 6, 1]/8` quadratic, mirrored at the ends), so
//! three passes replace a full stencil evaluation per node; radial bases are evaluated directly.

use rayon::prelude::*;

use crate::stencil::mirror;
use crate::{Basis, CoefficientVolume};

/// The field at every node (x fastest).
pub fn node_values(volume: &CoefficientVolume) -> Vec<f32> {
    let (side, centre) = match volume.basis {
        Basis::Trilinear => return volume.coeffs.clone(),
        Basis::Bspline2 => (1.0 / 8.0, 6.0 / 8.0),
        Basis::Bspline3 => (1.0 / 6.0, 4.0 / 6.0),
        Basis::Pg { .. } => return volume.sample(&volume.grid),
    };
    let dims = volume.grid.dims;
    let mut a = volume.coeffs.clone();
    let mut b = vec![0.0f32; a.len()];
    for axis in 0..3 {
        convolve_axis(&a, &mut b, dims, axis, side, centre);
        std::mem::swap(&mut a, &mut b);
    }
    a
}

/// `out = side · (prev + next) + centre · here` along `axis`, mirrored at the ends.
fn convolve_axis(
    input: &[f32],
    out: &mut [f32],
    dims: [usize; 3],
    axis: usize,
    side: f32,
    centre: f32,
) {
    let [nx, ny, nz] = dims;
    let stride = [1, nx, nx * ny][axis];
    let n = dims[axis];
    out.par_chunks_mut(nx * ny)
        .enumerate()
        .for_each(|(k, plane)| {
            for j in 0..ny {
                for i in 0..nx {
                    let at = [i, j, k][axis] as i64;
                    let base = i + nx * (j + ny * k) - at as usize * stride;
                    let prev = input[base + mirror(at - 1, n) * stride];
                    let next = input[base + mirror(at + 1, n) * stride];
                    let here = input[base + at as usize * stride];
                    plane[i + nx * j] = side * (prev + next) + centre * here;
                }
            }
        });
    debug_assert_eq!(input.len(), nx * ny * nz);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Grid;
    use glam::Vec3;

    #[test]
    fn matches_direct_evaluation_for_every_basis() {
        let grid = Grid {
            origin: Vec3::new(-0.3, 0.1, 0.2),
            spacing: 0.07,
            dims: [5, 4, 6],
        };
        let coeffs: Vec<f32> = (0..grid.len())
            .map(|i| ((i * 37) % 11) as f32 * 0.1 - 0.5)
            .collect();
        for basis in [
            Basis::Trilinear,
            Basis::Bspline2,
            Basis::Bspline3,
            Basis::Pg { n: 3, r: 1.5 },
        ] {
            let vol = CoefficientVolume::new(grid, basis, coeffs.clone()).unwrap();
            let fast = node_values(&vol);
            let direct = vol.sample(&grid);
            for (f, d) in fast.iter().zip(&direct) {
                assert!((f - d).abs() < 1e-5, "{basis}: {f} vs {d}");
            }
        }
    }
}
