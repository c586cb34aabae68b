//! A map of a field's node values interpolated again in the same basis, one layer of fitting
//! groups at a time: the node values are held only within the reach of the layer being fitted,
//! so memory is the input, the result and a window, not a second copy of the volume.

use glam::Vec3;
use pgvol_core::progress::{Report, Span};
use pgvol_core::sparse::{BrickValues, SparseGrid, BRICK_NODES};
use pgvol_core::{Background, BRICK_EDGE};
use pgvol_field::fit::{
    brick_node_values, interp_sparse, interp_sparse_groups, node_values_sparse, sparse_reach,
    SPARSE_GROUP,
};
use pgvol_field::{Basis, CoefficientVolume, Grid};
use rayon::prelude::*;

use crate::error::OpsError;

/// The node values of `volume` mapped by `f` and interpolated again, brick by brick: the bricks
/// whose node values vary are mapped node by node, every other brick is its side's background
/// mapped once. `varies(lo, hi, v)` says whether `f` could change with position over the box
/// `[lo, hi]` for the node value `v` (drains crossing far space). Bit for bit the whole grid's
/// interpolation of the whole grid's mapped node values; separable bases are fitted a layer of
/// groups at a time, pseudo-Gaussians (a global solve) as a whole.
///
/// The groups fitted are reported to `report`, which is polled for a stop per group: a stopped
/// remap returns at once with what is done so far, for the caller to discard.
pub(crate) fn remap(
    volume: &CoefficientVolume,
    f: impl Fn(Vec3, f32) -> f32 + Sync,
    varies: impl Fn(Vec3, Vec3, f32) -> bool + Sync,
    report: Report,
) -> Result<CoefficientVolume, OpsError> {
    if matches!(volume.basis, Basis::Pg { .. }) {
        return remap_whole(volume, f, varies, report);
    }
    let grid = volume.grid;
    let coeffs = &volume.coeffs;
    let [_, by, bz] = coeffs.brick_counts();
    let background = coeffs.background();
    let mut window = coeffs.sides_only();
    window.set_background(Background {
        outside: f(grid.origin, background.outside),
        inside: f(grid.origin, background.inside),
    });
    let mut out = window.sides_only();
    let mut stored_by_layer: Vec<Vec<[u32; 2]>> = vec![Vec::new(); bz];
    for (b, _) in coeffs.stored() {
        stored_by_layer[b[2]].push([b[1] as u32, b[0] as u32]);
    }
    let reach = sparse_reach(volume.basis);
    let groups_y = 0..by.div_ceil(SPARSE_GROUP);
    let mut held_to = 0;
    let layers = bz.div_ceil(SPARSE_GROUP);
    for gz in 0..layers {
        if report.cancelled() {
            break;
        }
        let from = (gz * SPARSE_GROUP).saturating_sub(reach);
        let to = ((gz + 1) * SPARSE_GROUP + reach).min(bz);
        window.retain(|b, _| b[2] >= from);
        for k in held_to.max(from)..to {
            for (b, values) in mapped_layer(volume, &stored_by_layer, k, &f, &varies) {
                window.insert(b, values);
            }
        }
        held_to = to;
        let part =
            Span::whole(report).part(gz as f64 / layers as f64, (gz + 1) as f64 / layers as f64);
        let (bricks, _) = interp_sparse_groups(
            grid,
            volume.basis,
            &window,
            groups_y.clone(),
            gz..gz + 1,
            &part,
        )?;
        for (b, values) in bricks {
            out.insert(b, values);
        }
    }
    Ok(CoefficientVolume::from_sparse(grid, volume.basis, out)?)
}

/// [`remap`] over the whole grid at once.
pub(crate) fn remap_whole(
    volume: &CoefficientVolume,
    f: impl Fn(Vec3, f32) -> f32 + Sync,
    varies: impl Fn(Vec3, Vec3, f32) -> bool + Sync,
    report: Report,
) -> Result<CoefficientVolume, OpsError> {
    let mut values = node_values_sparse(volume);
    map_nodes(&mut values, volume.grid, f, varies);
    let (result, _) = interp_sparse(volume.grid, volume.basis, &values, report)?;
    Ok(result)
}

/// The node values `values` on `grid` mapped by `f` in place, as [`remap_whole`] does before
/// interpolating.
pub(crate) fn map_nodes(
    values: &mut SparseGrid,
    grid: Grid,
    f: impl Fn(Vec3, f32) -> f32 + Sync,
    varies: impl Fn(Vec3, Vec3, f32) -> bool + Sync,
) {
    let background = values.background();
    // Absent bricks where `f` depends on position become stored bricks of their background.
    // Visited layer by layer rather than listed: a 4096³ grid has 134 million bricks.
    let [bx, by, bz] = values.brick_counts();
    let moving: Vec<[usize; 3]> = (0..bz)
        .into_par_iter()
        .filter(|&k| layer_varies(values, grid, k, &varies))
        .flat_map_iter(|k| {
            let values = &*values;
            let varies = &varies;
            (0..by)
                .flat_map(move |j| (0..bx).map(move |i| [i, j, k]))
                .filter(move |&b| !values.is_stored(b) && brick_varies(values, grid, b, varies))
        })
        .collect();
    for b in moving {
        values.brick_or_background(b);
    }
    let mut bricks: Vec<([usize; 3], &mut BrickValues)> = values.stored_mut().collect();
    bricks
        .par_iter_mut()
        .for_each(|(b, v)| map_brick(grid, *b, v, &f));
    drop(bricks);
    values.set_background(Background {
        outside: f(grid.origin, background.outside),
        inside: f(grid.origin, background.inside),
    });
}

/// The mapped node values of the bricks of layer `k` that the whole grid's node values store:
/// those within one brick of a stored coefficient brick (`stored` lists them by layer as
/// `[j, i]`), and those of the other bricks where `f` varies, from their background.
fn mapped_layer(
    volume: &CoefficientVolume,
    stored: &[Vec<[u32; 2]>],
    k: usize,
    f: &(impl Fn(Vec3, f32) -> f32 + Sync),
    varies: &(impl Fn(Vec3, Vec3, f32) -> bool + Sync),
) -> Vec<([usize; 3], Box<BrickValues>)> {
    let coeffs = &volume.coeffs;
    let grid = volume.grid;
    let [bx, by, _] = coeffs.brick_counts();
    let mut near: Vec<[usize; 2]> = Vec::new();
    for layer in &stored[k.saturating_sub(1)..(k + 2).min(stored.len())] {
        for &[j, i] in layer {
            let [j, i] = [j as usize, i as usize];
            for nj in j.saturating_sub(1)..(j + 2).min(by) {
                for ni in i.saturating_sub(1)..(i + 2).min(bx) {
                    near.push([nj, ni]);
                }
            }
        }
    }
    near.sort_unstable();
    near.dedup();
    let rows = if layer_varies(coeffs, grid, k, varies) {
        0..by
    } else {
        0..0
    };
    let moving: Vec<[usize; 2]> = rows
        .into_par_iter()
        .flat_map_iter(|j| {
            let near = &near;
            (0..bx).map(move |i| [j, i]).filter(move |&[j, i]| {
                near.binary_search(&[j, i]).is_err()
                    && brick_varies(coeffs, grid, [i, j, k], varies)
            })
        })
        .collect();
    near.par_iter()
        .map(|&[j, i]| (true, [i, j, k]))
        .chain(moving.par_iter().map(|&[j, i]| (false, [i, j, k])))
        .map(|(is_near, b)| {
            let mut values = if is_near {
                Box::new(brick_node_values(volume, b))
            } else {
                Box::new([coeffs.background_of(b); BRICK_NODES])
            };
            map_brick(grid, b, &mut values, f);
            (b, values)
        })
        .collect()
}

/// Whether `f` may vary with position anywhere in brick layer `k` of `values`, for either
/// background: where it cannot over the layer's box, it cannot over any of its bricks, and the
/// layer's bricks are not asked one by one (a 4096³ grid has 262,144 bricks per layer).
fn layer_varies(
    values: &SparseGrid,
    grid: Grid,
    k: usize,
    varies: &(impl Fn(Vec3, Vec3, f32) -> bool + Sync),
) -> bool {
    let [nx, ny, nz] = grid.dims;
    let (z0, z1) = (k * BRICK_EDGE, ((k + 1) * BRICK_EDGE).min(nz) - 1);
    let (lo, hi) = (grid.point(0, 0, z0), grid.point(nx - 1, ny - 1, z1));
    let background = values.background();
    varies(lo, hi, background.outside) || varies(lo, hi, background.inside)
}

/// Whether `f` may vary with position over absent brick `b` of `values` (see [`remap`]).
fn brick_varies(
    values: &SparseGrid,
    grid: Grid,
    b: [usize; 3],
    varies: &(impl Fn(Vec3, Vec3, f32) -> bool + Sync),
) -> bool {
    let (lo, n) = values.brick_extent(b);
    let hi = [0, 1, 2].map(|a| lo[a] + n[a] - 1);
    varies(
        grid.point(lo[0], lo[1], lo[2]),
        grid.point(hi[0], hi[1], hi[2]),
        values.background_of(b),
    )
}

/// Brick `b`'s node values mapped by `f` in place, every slot of the brick (those past the
/// grid's end included).
fn map_brick(grid: Grid, b: [usize; 3], values: &mut BrickValues, f: &impl Fn(Vec3, f32) -> f32) {
    let lo = b.map(|c| c * BRICK_EDGE);
    for (at, x) in values.iter_mut().enumerate() {
        let n = [
            at % BRICK_EDGE,
            (at / BRICK_EDGE) % BRICK_EDGE,
            at / (BRICK_EDGE * BRICK_EDGE),
        ];
        *x = f(grid.point(lo[0] + n[0], lo[1] + n[1], lo[2] + n[2]), *x);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_core::progress::QUIET;

    /// A ball's signed distance encoded in a band, on a grid of several layers of groups.
    fn ball(n: usize, basis: Basis) -> CoefficientVolume {
        let grid = Grid::cube_res(Vec3::ZERO, Vec3::ONE, n).unwrap();
        let centre = Vec3::splat(0.5);
        let band = 4.0 * grid.spacing;
        let mut samples = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let d = (grid.point(i, j, k) - centre).length() - 0.35;
                    samples.push(d.clamp(-band, band));
                }
            }
        }
        let samples =
            SparseGrid::from_dense_where(grid.dims, &samples, Background::clamp(band), |b| {
                let c = grid.point(
                    b[0] * BRICK_EDGE + 4,
                    b[1] * BRICK_EDGE + 4,
                    b[2] * BRICK_EDGE + 4,
                );
                let d = (c - centre).length() - 0.35;
                if d.abs() < 1.5 * BRICK_EDGE as f32 * grid.spacing {
                    Some(true)
                } else {
                    (d > 0.0).then_some(false)
                }
            });
        interp_sparse(grid, basis, &samples, QUIET).unwrap().0
    }

    #[test]
    fn layer_by_layer_is_the_whole_grid_bit_for_bit() {
        for basis in [Basis::Bspline3, Basis::Bspline2, Basis::Trilinear] {
            // 150 nodes: 19 bricks, three layers of groups along z.
            let volume = ball(150, basis);
            assert!(volume.coeffs.brick_counts()[2] > 2 * SPARSE_GROUP);
            let f = |_: Vec3, v: f32| (v + 0.01).abs() - 0.01;
            let layered = remap(&volume, f, |_, _, _| false, QUIET).unwrap();
            let whole = remap_whole(&volume, f, |_, _, _| false, QUIET).unwrap();
            assert!(layered.coeffs.stored_count() > 0);
            assert_eq!(layered.coeffs.stored_count(), whole.coeffs.stored_count());
            assert!(layered.coeffs == whole.coeffs, "{basis:?}");
            // A map that varies with position far from the surface (a drain's half-line).
            let drain = |p: Vec3, v: f32| v.max(0.02 - (p - Vec3::new(0.5, 0.5, p.z)).length());
            let reaches = |lo: Vec3, hi: Vec3, _: f32| {
                lo.x <= 0.53 && hi.x >= 0.47 && lo.y <= 0.53 && hi.y >= 0.47
            };
            let layered = remap(&volume, drain, reaches, QUIET).unwrap();
            let whole = remap_whole(&volume, drain, reaches, QUIET).unwrap();
            assert!(layered.coeffs == whole.coeffs, "{basis:?} with a drain");
        }
    }
}
