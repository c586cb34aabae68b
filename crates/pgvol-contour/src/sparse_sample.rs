//! Sampling a coefficient volume only where the level set can pass.
//!
//! For the B-spline and trilinear bases every field value is a convex combination of the
//! coefficients in its support (non-negative weights summing to one), so a block of nodes whose
//! supporting coefficients all lie above (below) the iso value lies entirely above (below) it.
//! Such blocks need no evaluation; they are filled with that bound, which keeps every sign and so
//! every crossing of the level set.

use pgvol_field::{CoefficientVolume, Grid};
use rayon::prelude::*;

/// Nodes per block edge.
const BLOCK: usize = 8;

/// The field on `grid` (x fastest), evaluated exactly in blocks the `iso` level set may cross and
/// bounded elsewhere. Bases without non-negative, unit-sum weights are evaluated everywhere.
pub fn sample_near_level(volume: &CoefficientVolume, grid: &Grid, iso: f32) -> Vec<f32> {
    if !volume.basis.is_separable() {
        return volume.sample(grid);
    }
    let [nx, ny, nz] = grid.dims;
    let blocks = [nx.div_ceil(BLOCK), ny.div_ceil(BLOCK), nz.div_ceil(BLOCK)];
    let span = |b: usize, n: usize| (b * BLOCK, ((b + 1) * BLOCK).min(n));
    let filled: Vec<(usize, Vec<f32>)> = (0..blocks[0] * blocks[1] * blocks[2])
        .into_par_iter()
        .map(|b| {
            let (bi, bj, bk) = (
                b % blocks[0],
                (b / blocks[0]) % blocks[1],
                b / (blocks[0] * blocks[1]),
            );
            let (x, y, z) = (span(bi, nx), span(bj, ny), span(bk, nz));
            let lo = grid.point(x.0, y.0, z.0);
            let hi = grid.point(x.1 - 1, y.1 - 1, z.1 - 1);
            let n = (x.1 - x.0) * (y.1 - y.0) * (z.1 - z.0);
            if let Some(bound) = one_sided_bound(volume, lo, hi, iso) {
                return (b, vec![bound; n]);
            }
            let mut out = Vec::with_capacity(n);
            for k in z.0..z.1 {
                for j in y.0..y.1 {
                    for i in x.0..x.1 {
                        out.push(volume.value(grid.point(i, j, k)));
                    }
                }
            }
            (b, out)
        })
        .collect();
    let mut values = vec![0.0f32; grid.len()];
    for (b, block) in filled {
        let (bi, bj, bk) = (
            b % blocks[0],
            (b / blocks[0]) % blocks[1],
            b / (blocks[0] * blocks[1]),
        );
        let (x, y, z) = (span(bi, nx), span(bj, ny), span(bk, nz));
        let w = x.1 - x.0;
        let mut at = 0;
        for k in z.0..z.1 {
            for j in y.0..y.1 {
                let row = grid.index(x.0, j, k);
                values[row..row + w].copy_from_slice(&block[at..at + w]);
                at += w;
            }
        }
    }
    values
}

/// If every coefficient that can touch a point of the box `[lo, hi]` is above `iso`, their
/// minimum (a lower bound of the field there); if all are below, their maximum; else `None`.
/// Points outside the volume's grid only add their (positive) distance to the box, so a
/// one-sided bound found from the clamped box still holds for outside-positive values.
fn one_sided_bound(
    volume: &CoefficientVolume,
    lo: glam::Vec3,
    hi: glam::Vec3,
    iso: f32,
) -> Option<f32> {
    let g = &volume.grid;
    let (ulo, uhi) = (g.to_grid(lo), g.to_grid(hi));
    // Every basis here reaches at most 2 nodes from the cell holding the point; mirrored indices
    // beyond the border repeat coefficients inside it, so the clamped range covers them.
    let range = |a: f32, b: f32, n: usize| {
        let first = (a.floor() as i64 - 2).clamp(0, n as i64 - 1) as usize;
        let last = (b.ceil() as i64 + 2).clamp(0, n as i64 - 1) as usize;
        (first, last)
    };
    let (i0, i1) = range(ulo.x, uhi.x, g.dims[0]);
    let (j0, j1) = range(ulo.y, uhi.y, g.dims[1]);
    let (k0, k1) = range(ulo.z, uhi.z, g.dims[2]);
    let (mut min, mut max) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut row = vec![0.0f32; i1 - i0 + 1];
    for k in k0..=k1 {
        for j in j0..=j1 {
            volume
                .coeffs
                .gather([i0, j, k], [row.len(), 1, 1], &mut row);
            for &c in &row {
                min = min.min(c);
                max = max.max(c);
            }
        }
        if min <= iso && max >= iso {
            return None;
        }
    }
    if min > iso {
        Some(min)
    } else if max < iso {
        // Outside the grid box values grow with distance, so a negative bound could be wrong
        // there; the sampling grids used here lie within the box.
        Some(max)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_volumes::two_balls;
    use pgvol_field::Basis;

    #[test]
    fn signs_match_full_sampling_and_values_match_near_the_surface() {
        for basis in [Basis::Trilinear, Basis::Bspline2, Basis::Bspline3] {
            let v = two_balls(basis);
            for iso in [0.0, 0.1, -0.05] {
                let full = v.sample(&v.grid);
                let sparse = sample_near_level(&v, &v.grid, iso);
                let mut exact = 0;
                for (f, s) in full.iter().zip(&sparse) {
                    assert_eq!(*f > iso, *s > iso, "{basis:?} iso {iso}: {f} vs {s}");
                    if f == s {
                        exact += 1;
                    }
                }
                assert!(exact < full.len(), "{basis:?}: nothing was skipped");
            }
        }
    }
}
