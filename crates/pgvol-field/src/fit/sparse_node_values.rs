//! The field at the nodes of its own grid, brick by brick, for sparse volumes. A separable
//! B-spline at the nodes is a 3-tap blur of the coefficients; a brick of constant coefficients
//! with constant neighbours blurs to the same constant, so only the stored bricks and the bricks
//! touching them need work, and every other brick keeps its background.

use pgvol_core::sparse::BrickValues;
use pgvol_core::{SparseGrid, BRICK_EDGE, BRICK_NODES};
use rayon::prelude::*;

use super::node_values::taps;
use crate::stencil::mirror;
use crate::volume::CoefficientVolume;

/// Window edge: one brick and one node either side.
const WIN: usize = BRICK_EDGE + 2;

/// The field at every node, as a sparse grid with the coefficients' background and sides:
/// stored where a stored coefficient brick is within one brick. Pseudo-Gaussians do not sum to
/// one, so constant coefficients do not give that constant: every brick is computed for them.
pub fn node_values_sparse(volume: &CoefficientVolume) -> SparseGrid {
    let coeffs = &volume.coeffs;
    let mut out = coeffs.clone();
    let bricks = match taps(volume.basis) {
        Some(_) => touched_bricks(coeffs),
        None => coeffs.all_bricks().collect(),
    };
    let computed: Vec<([usize; 3], Box<BrickValues>)> = bricks
        .par_iter()
        .map(|&b| (b, Box::new(brick_node_values(volume, b))))
        .collect();
    for (b, v) in computed {
        out.insert(b, v);
    }
    out
}

/// Stored bricks and their 26 neighbours, in brick order.
pub(crate) fn touched_bricks(grid: &SparseGrid) -> Vec<[usize; 3]> {
    let counts = grid.brick_counts();
    let mut touched: Vec<[usize; 3]> = Vec::with_capacity(grid.stored_count() * 3);
    for (b, _) in grid.stored() {
        for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let n = [b[0] as i64 + dx, b[1] as i64 + dy, b[2] as i64 + dz];
                    if (0..3).all(|a| n[a] >= 0 && (n[a] as usize) < counts[a]) {
                        touched.push(n.map(|c| c as usize));
                    }
                }
            }
        }
    }
    touched.sort_unstable_by_key(|b| (b[2], b[1], b[0]));
    touched.dedup();
    touched
}

/// The field at the nodes of brick `b` of the volume's own grid (nodes past the grid's end hold
/// the brick's background).
pub fn brick_node_values(volume: &CoefficientVolume, b: [usize; 3]) -> BrickValues {
    let coeffs = &volume.coeffs;
    let (lo, n) = coeffs.brick_extent(b);
    let mut out = [coeffs.background_of(b); BRICK_NODES];
    let Some((side, centre)) = taps(volume.basis) else {
        // Radial bases: evaluated directly.
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let p = volume.grid.point(lo[0] + i, lo[1] + j, lo[2] + k);
                    out[i + BRICK_EDGE * (j + BRICK_EDGE * k)] = volume.value(p);
                }
            }
        }
        return out;
    };
    let dims = coeffs.dims();
    // The window's nodes per axis, mirrored at the grid's ends as the basis is.
    let index = |a: usize, t: usize| mirror(lo[a] as i64 - 1 + t as i64, dims[a]);
    let first = [0, 1, 2].map(|a| lo[a].saturating_sub(1));
    let last = [0, 1, 2].map(|a| (lo[a] + n[a] + 1).min(dims[a]));
    let size = [0, 1, 2].map(|a| last[a] - first[a]);
    let mut gathered = vec![0.0f32; size[0] * size[1] * size[2]];
    coeffs.gather(first, size, &mut gathered);
    let mut win = [0.0f32; WIN * WIN * WIN];
    for z in 0..n[2] + 2 {
        let gz = index(2, z) - first[2];
        for y in 0..n[1] + 2 {
            let gy = index(1, y) - first[1];
            for x in 0..n[0] + 2 {
                let gx = index(0, x) - first[0];
                win[x + WIN * (y + WIN * z)] = gathered[gx + size[0] * (gy + size[1] * gz)];
            }
        }
    }
    let blur = |a: f32, c: f32, d: f32| side * (a + d) + centre * c;
    let mut xs = [0.0f32; WIN * WIN * WIN];
    for z in 0..n[2] + 2 {
        for y in 0..n[1] + 2 {
            for x in 1..=n[0] {
                let at = x + WIN * (y + WIN * z);
                xs[at] = blur(win[at - 1], win[at], win[at + 1]);
            }
        }
    }
    let mut ys = [0.0f32; WIN * WIN * WIN];
    for z in 0..n[2] + 2 {
        for y in 1..=n[1] {
            for x in 1..=n[0] {
                let at = x + WIN * (y + WIN * z);
                ys[at] = blur(xs[at - WIN], xs[at], xs[at + WIN]);
            }
        }
    }
    let plane = WIN * WIN;
    for z in 1..=n[2] {
        for y in 1..=n[1] {
            for x in 1..=n[0] {
                let at = x + WIN * (y + WIN * z);
                out[(x - 1) + BRICK_EDGE * ((y - 1) + BRICK_EDGE * (z - 1))] =
                    blur(ys[at - plane], ys[at], ys[at + plane]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::basis::Basis;
    use crate::fit::node_values;
    use glam::Vec3;
    use pgvol_core::{Background, Grid};

    #[test]
    fn match_the_dense_node_values_for_every_basis_and_leave_far_bricks_alone() {
        for dims in [[21, 17, 30], [9, 9, 9], [2, 12, 5]] {
            let grid = Grid {
                origin: Vec3::new(-0.3, 0.1, 0.2),
                spacing: 0.07,
                dims,
                offset: Default::default(),
            };
            let dense: Vec<f32> = (0..grid.len())
                .map(|i| ((i * 37) % 11) as f32 * 0.1 - 0.5)
                .collect();
            for basis in [
                Basis::Trilinear,
                Basis::Bspline2,
                Basis::Bspline3,
                Basis::Pg { n: 3, r: 1.5 },
            ] {
                // Keep one brick in three; the others become the background of their side.
                let mut coeffs = SparseGrid::from_dense(dims, &dense, Background::clamp(0.6));
                let mut turn = 0;
                coeffs.retain(|_, _| {
                    turn += 1;
                    turn % 3 != 0
                });
                let vol = CoefficientVolume::from_sparse(grid, basis, coeffs).unwrap();
                let want = node_values(&vol);
                let got = node_values_sparse(&vol).to_dense();
                for (i, (a, b)) in want.iter().zip(&got).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-6,
                        "{basis:?} {dims:?} node {i}: {a} vs {b}"
                    );
                }
            }
        }
        // A single stored brick in a large grid: only it and its neighbours are computed.
        let dims = [200, 200, 200];
        let grid = Grid {
            origin: Vec3::ZERO,
            spacing: 1.0,
            dims,
            offset: Default::default(),
        };
        let mut coeffs = SparseGrid::new(dims, Background::clamp(3.0));
        coeffs.insert([10, 10, 10], Box::new([0.5; BRICK_NODES]));
        let vol = CoefficientVolume::from_sparse(grid, Basis::Bspline3, coeffs).unwrap();
        let values = node_values_sparse(&vol);
        assert_eq!(values.stored_count(), 27);
        assert_eq!(values.get([0, 0, 0]), 3.0);
        assert_eq!(values.get([84, 84, 84]), 0.5);
        assert!((values.get([79, 84, 84]) - (3.0 * 5.0 / 6.0 + 0.5 / 6.0)).abs() < 1e-6);
    }
}
