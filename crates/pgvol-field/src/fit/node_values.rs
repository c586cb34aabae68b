//! The field at every node of its own grid. A separable B-spline at the nodes is a 3-tap
//! convolution per axis (`[1, 4, 1]/6` cubic, `[1, 6, 1]/8` quadratic, mirrored at the ends), so
//! three passes replace a full stencil evaluation per node; radial bases are evaluated directly.

use rayon::prelude::*;

use crate::basis::Basis;
use crate::stencil::mirror;
use crate::volume::CoefficientVolume;

/// Z-planes per task: the x and y passes of the two planes either side are redone per task.
const PLANES: usize = 8;

/// The field at every node (x fastest).
pub fn node_values(volume: &CoefficientVolume) -> Vec<f32> {
    let Some(taps) = taps(volume.basis) else {
        return direct(volume);
    };
    let [nx, ny, _] = volume.grid.dims;
    let plane = nx * ny;
    let mut out = vec![0.0f32; volume.grid.len()];
    out.par_chunks_mut(PLANES * plane)
        .enumerate()
        .for_each(|(t, chunk)| {
            let first = t * PLANES;
            let planes = first..first + chunk.len() / plane;
            node_planes(volume, taps, planes, |k, values| {
                chunk[(k - first) * plane..][..plane].copy_from_slice(values);
            });
        });
    out
}

/// How many nodes `f(node value, index)` holds for, counted without storing the field.
pub(crate) fn count_nodes(
    volume: &CoefficientVolume,
    f: impl Fn(f32, usize) -> bool + Sync,
) -> usize {
    let Some(taps) = taps(volume.basis) else {
        return direct(volume)
            .par_iter()
            .enumerate()
            .filter(|&(i, &v)| f(v, i))
            .count();
    };
    let [nx, ny, nz] = volume.grid.dims;
    let plane = nx * ny;
    (0..nz.div_ceil(PLANES))
        .into_par_iter()
        .map(|t| {
            let mut count = 0;
            let planes = t * PLANES..((t + 1) * PLANES).min(nz);
            node_planes(volume, taps, planes, |k, values| {
                count += values
                    .iter()
                    .enumerate()
                    .filter(|&(i, &v)| f(v, k * plane + i))
                    .count();
            });
            count
        })
        .sum()
}

/// The 3-tap node kernel `(side, centre)` of a separable basis, `None` for bases evaluated
/// directly.
pub(crate) fn taps(basis: Basis) -> Option<(f32, f32)> {
    match basis {
        Basis::Trilinear => Some((0.0, 1.0)),
        Basis::Bspline2 => Some((1.0 / 8.0, 6.0 / 8.0)),
        Basis::Bspline3 => Some((1.0 / 6.0, 4.0 / 6.0)),
        Basis::Pg { .. } => None,
    }
}

fn direct(volume: &CoefficientVolume) -> Vec<f32> {
    volume.sample(&volume.grid)
}

/// Calls `sink(k, field on z-plane k)` for the planes `planes` in order: the x and y passes
/// plane by plane, kept for the three planes the z pass reads, so no volume-sized buffer is
/// needed. Each node gets the operations of three whole-volume passes, bit for bit.
fn node_planes(
    volume: &CoefficientVolume,
    (side, centre): (f32, f32),
    planes: std::ops::Range<usize>,
    mut sink: impl FnMut(usize, &[f32]),
) {
    let [nx, ny, nz] = volume.grid.dims;
    let plane = nx * ny;
    if side == 0.0 {
        // Trilinear: the coefficients are the node values.
        let mut coeffs = vec![0.0f32; plane];
        for k in planes {
            volume.coeffs.gather([0, 0, k], [nx, ny, 1], &mut coeffs);
            sink(k, &coeffs);
        }
        return;
    }
    let mut row_pass = vec![0.0f32; plane];
    let mut coeffs = vec![0.0f32; plane];
    // The xy-filtered planes k − 1, k, k + 1 (mirrored), by plane index.
    let mut window: [(usize, Vec<f32>); 3] =
        std::array::from_fn(|_| (usize::MAX, vec![0.0; plane]));
    let mut out = vec![0.0f32; plane];
    for k in planes {
        let wanted = [mirror(k as i64 - 1, nz), k, mirror(k as i64 + 1, nz)];
        for &m in &wanted {
            if window.iter().any(|(at, _)| *at == m) {
                continue;
            }
            let slot = (0..3)
                .find(|&s| !wanted.contains(&window[s].0))
                .expect("three planes fit");
            volume.coeffs.gather([0, 0, m], [nx, ny, 1], &mut coeffs);
            for (row, input) in row_pass.chunks_mut(nx).zip(coeffs.chunks(nx)) {
                blur_row(input, row, side, centre);
            }
            let xy = &mut window[slot].1;
            for j in 0..ny {
                let (p, n) = (mirror(j as i64 - 1, ny), mirror(j as i64 + 1, ny));
                let line = |j: usize| &row_pass[nx * j..][..nx];
                blend(
                    &mut xy[nx * j..][..nx],
                    line(p),
                    line(j),
                    line(n),
                    side,
                    centre,
                );
            }
            window[slot].0 = m;
        }
        let get = |m: usize| &window.iter().find(|(at, _)| *at == m).expect("loaded").1;
        blend(
            &mut out,
            get(wanted[0]),
            get(k),
            get(wanted[2]),
            side,
            centre,
        );
        sink(k, &out);
    }
}

/// `out = side · (prev + next) + centre · here`, element by element.
#[inline]
fn blend(out: &mut [f32], prev: &[f32], here: &[f32], next: &[f32], side: f32, centre: f32) {
    for (o, ((p, h), n)) in out.iter_mut().zip(prev.iter().zip(here).zip(next)) {
        *o = side * (p + n) + centre * h;
    }
}

/// The x pass along one row, mirrored at the ends.
fn blur_row(here: &[f32], out: &mut [f32], side: f32, centre: f32) {
    let nx = here.len();
    if nx < 3 {
        for (i, o) in out.iter_mut().enumerate() {
            let prev = here[mirror(i as i64 - 1, nx)];
            let next = here[mirror(i as i64 + 1, nx)];
            *o = side * (prev + next) + centre * here[i];
        }
        return;
    }
    blend(
        &mut out[1..nx - 1],
        &here[..nx - 2],
        &here[1..nx - 1],
        &here[2..],
        side,
        centre,
    );
    // Mirrored ends: both neighbours are the one inside.
    out[0] = side * (here[1] + here[1]) + centre * here[0];
    out[nx - 1] = side * (here[nx - 2] + here[nx - 2]) + centre * here[nx - 1];
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use pgvol_core::Grid;

    /// Short axes (2 nodes) take the mirrored neighbours on both sides.
    #[test]
    fn matches_direct_evaluation_for_every_basis() {
        for dims in [[5, 4, 6], [2, 3, 7], [9, 2, 3], [4, 3, 2 * PLANES + 3]] {
            let grid = Grid {
                origin: Vec3::new(-0.3, 0.1, 0.2),
                spacing: 0.07,
                dims,
                offset: Default::default(),
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
                    assert!((f - d).abs() < 1e-5, "{basis} {dims:?}: {f} vs {d}");
                }
                // Counting sees the same values as storing them.
                let below = |v: f32, i: usize| v < coeffs[(i * 7) % coeffs.len()];
                let stored = (0..fast.len()).filter(|&i| below(fast[i], i)).count();
                assert!(stored > 0, "{basis} {dims:?}");
                assert_eq!(count_nodes(&vol, below), stored, "{basis} {dims:?}");
            }
        }
    }

    /// Plane by plane gives the bits of three whole-volume passes, one axis at a time.
    #[test]
    fn planes_give_the_bits_of_whole_volume_passes() {
        // Two whole tasks of planes and a short one.
        let dims = [7, 5, 2 * PLANES + 5];
        let grid = Grid {
            origin: Vec3::ZERO,
            spacing: 0.1,
            dims,
            offset: Default::default(),
        };
        let coeffs: Vec<f32> = (0..grid.len())
            .map(|i| ((i * 7919) % 101) as f32 * 0.013 - 0.6)
            .collect();
        let (side, centre) = (1.0f32 / 6.0, 4.0f32 / 6.0);
        let mut want = coeffs.clone();
        let [nx, ny, _] = dims;
        for axis in 0..3 {
            let input = want.clone();
            let (stride, n) = ([1, nx, nx * ny][axis], dims[axis]);
            for (idx, out) in want.iter_mut().enumerate() {
                let at = [idx % nx, (idx / nx) % ny, idx / (nx * ny)][axis];
                let base = idx - at * stride;
                let prev = input[base + mirror(at as i64 - 1, n) * stride];
                let next = input[base + mirror(at as i64 + 1, n) * stride];
                *out = side * (prev + next) + centre * input[idx];
            }
        }
        let vol = CoefficientVolume::new(grid, Basis::Bspline3, coeffs).unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&node_values(&vol)), bits(&want));
    }
}
