//! A certificate of wrong signs in a sampled grid.
//!
//! Distance is 1-Lipschitz: if two neighbouring nodes `h` apart have opposite signs, the surface
//! crosses the segment between them, so `|a| + |b| ≤ h`. A pair breaking that bound proves one of
//! the two signs wrong (the magnitudes are exact, or clamped at a value beyond the band). The
//! pseudonormal sign relies on the mesh bounding a solid; a closed, consistently oriented mesh
//! that folds over or crosses itself breaks it, and this check catches the resulting regions of
//! flipped sign wherever they reach beyond one cell of the surface.

use rayon::prelude::*;

use pgvol_core::sparse::BrickValues;
use pgvol_core::{SparseGrid, BRICK_EDGE};

use crate::grid::Grid;

/// Relative slack on the bound for float rounding of exact distances.
const SLACK: f32 = 1e-3;

/// Neighbouring node pairs (along x, y and z) whose signs differ although `|a| + |b|` exceeds the
/// spacing: each proves a wrong sign.
pub fn sign_contradictions(grid: &Grid, values: &[f32]) -> usize {
    let [nx, ny, nz] = grid.dims;
    if values.len() != nx * ny * nz {
        return 0;
    }
    let limit = grid.spacing * (1.0 + SLACK);
    let broken = |a: f32, b: f32| (a < 0.0) != (b < 0.0) && a.abs() + b.abs() > limit;
    let plane = nx * ny;
    (0..nz)
        .into_par_iter()
        .map(|k| {
            let mut count = 0;
            for j in 0..ny {
                for i in 0..nx {
                    let at = i + nx * j + plane * k;
                    let v = values[at];
                    count += usize::from(i + 1 < nx && broken(v, values[at + 1]));
                    count += usize::from(j + 1 < ny && broken(v, values[at + nx]));
                    count += usize::from(k + 1 < nz && broken(v, values[at + plane]));
                }
            }
            count
        })
        .sum()
}

/// As [`sign_contradictions`] on a sparse grid, without visiting the nodes of absent bricks:
/// inside such a brick all values are equal, so only its faces can hold a contradiction.
pub fn sparse_sign_contradictions(grid: &Grid, values: &SparseGrid) -> usize {
    sparse_sign_contradictions_in(grid, values, 0..usize::MAX, 0..usize::MAX)
}

/// The part of [`sparse_sign_contradictions`] counted from the bricks whose y and z brick
/// indices lie in `ys` and `zs` (each pair is counted from its lower brick), which needs the
/// bricks one past them in y and z too. Summed over boxes that tile the grid, it is the whole
/// grid's count.
pub fn sparse_sign_contradictions_in(
    grid: &Grid,
    values: &SparseGrid,
    ys: std::ops::Range<usize>,
    zs: std::ops::Range<usize>,
) -> usize {
    let dims = grid.dims;
    if values.dims() != dims {
        return 0;
    }
    let limit = grid.spacing * (1.0 + SLACK);
    let broken = |a: f32, b: f32| (a < 0.0) != (b < 0.0) && a.abs() + b.abs() > limit;
    let [bx, by, bz] = values.brick_counts();
    let ys = ys.start.min(by)..ys.end.min(by);
    let zs = zs.start.min(bz)..zs.end.min(bz);
    // Bricks by number, not listed: a list would hold 24 bytes per brick of the grid.
    let rows = ys.len();
    (0..bx * rows * zs.len())
        .into_par_iter()
        .map(|at| {
            let b = [
                at % bx,
                ys.start + (at / bx) % rows,
                zs.start + at / (bx * rows),
            ];
            let (lo, n) = values.brick_extent(b);
            let stored = values.is_stored(b);
            let mut count = 0;
            for axis in 0..3 {
                let mut next = b;
                next[axis] += 1;
                let neighbour_in_grid = lo[axis] + n[axis] < dims[axis];
                let pairs_nodes = stored || (neighbour_in_grid && values.is_stored(next));
                if !pairs_nodes {
                    // Absent against absent (or the border): one comparison for the face.
                    if neighbour_in_grid
                        && broken(values.background_of(b), values.background_of(next))
                    {
                        count += 1;
                    }
                    continue;
                }
                // Pairs (node, node + 1 along `axis`) with the first node in this brick; an
                // absent brick only pairs across its face.
                // Both bricks are looked up once; their nodes are read by offset.
                let first = if stored { 0 } else { n[axis] - 1 };
                let node = |brick: Option<&BrickValues>, fill: f32, l: [usize; 3]| {
                    brick.map_or(fill, |v| v[l[0] + BRICK_EDGE * (l[1] + BRICK_EDGE * l[2])])
                };
                let (here, here_fill) = (values.brick(b), values.background_of(b));
                let (there, there_fill) = if neighbour_in_grid {
                    (values.brick(next), values.background_of(next))
                } else {
                    (None, 0.0)
                };
                for k in 0..n[2] {
                    for j in 0..n[1] {
                        for i in 0..n[0] {
                            let mut l = [i, j, k];
                            if l[axis] < first {
                                continue;
                            }
                            let v = node(here, here_fill, l);
                            l[axis] += 1;
                            let w = if l[axis] < n[axis] {
                                node(here, here_fill, l)
                            } else if neighbour_in_grid {
                                l[axis] = 0;
                                node(there, there_fill, l)
                            } else {
                                continue;
                            };
                            count += usize::from(broken(v, w));
                        }
                    }
                }
            }
            count
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn grid(n: usize) -> Grid {
        Grid {
            origin: Vec3::ZERO,
            spacing: 1.0,
            dims: [n, n, n],
            offset: Default::default(),
        }
    }

    /// The exact SDF of the plane x = 2.3 on a unit grid.
    fn plane_values(n: usize) -> Vec<f32> {
        let mut v = Vec::with_capacity(n * n * n);
        for _k in 0..n {
            for _j in 0..n {
                for i in 0..n {
                    v.push(i as f32 - 2.3);
                }
            }
        }
        v
    }

    #[test]
    fn an_exact_field_has_no_contradictions() {
        assert_eq!(sign_contradictions(&grid(6), &plane_values(6)), 0);
    }

    #[test]
    fn a_flipped_node_away_from_the_surface_is_caught() {
        let g = grid(6);
        let mut v = plane_values(6);
        // Node (5, 2, 2) is 2.7 outside; flipping it contradicts its six neighbours but the
        // one beyond the grid edge.
        let at = 5 + 6 * 2 + 36 * 2;
        v[at] = -v[at];
        assert_eq!(sign_contradictions(&g, &v), 5);
    }

    #[test]
    fn a_flip_next_to_the_surface_is_allowed() {
        // Two nodes 0.3 and 0.7 from the plane on either side: consistent.
        assert_eq!(
            sign_contradictions(&grid(2), &[-0.3, 0.7, -0.3, 0.7, -0.3, 0.7, -0.3, 0.7]),
            0
        );
    }
}
