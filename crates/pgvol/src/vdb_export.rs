//! A field as an OpenVDB level set: the narrow band of nodes sampled leaf by leaf.
//!
//! OpenVDB leaves are 8³ voxels at multiples of 8, and a pgvol node is a voxel centre, so
//! each leaf is a block of nodes. With the B-spline and trilinear bases a value is a convex
//! combination of the coefficients that weigh on it, so a leaf whose supporting coefficients
//! all lie at or beyond the band's edge is a tile of its side, decided without evaluating the
//! field: only the leaves near the surface cost evaluations, whatever the grid's size.

use std::path::Path;

use pgvol_core::BRICK_EDGE;
use pgvol_field::{Basis, CoefficientVolume, Grid};
use pgvol_format::vdb::write::{
    write_level_set, LevelSetGrid, VdbCompression, VdbLeaf, VdbLeafValues,
};
use pgvol_format::vdb::{UniformScaleTranslate, LEAF_EDGE, LEAF_LOG2, LEAF_VOXELS};
use rayon::prelude::*;

use crate::error::{Error, FileResult, Result};

/// The band's half-width in voxels unless told otherwise, as OpenVDB's level-set tools use.
pub const VDB_BAND: f32 = 3.0;

/// The name of the grid written: the name OpenVDB-based tools (Houdini's "VDB from Polygons",
/// for one) give a level set, and the one to give Blender's Volume to Mesh.
pub const VDB_GRID_NAME: &str = "surface";

/// The widest band accepted, in voxels: beyond it a level set is a dense grid.
pub const MAX_VDB_BAND: f32 = 64.0;

/// Peak bytes per leaf near the surface while writing: its encoded buffer (mask, tags and up
/// to 512 values) and bookkeeping.
const BYTES_PER_VDB_LEAF: u64 = 2560;

const _: () = assert!(BRICK_EDGE == LEAF_EDGE);

/// Writes `volume` sampled on `grid` (the volume's grid or a resampling of its box) as an
/// OpenVDB FloatGrid level set at `path`: nodes within `band` voxels of the surface active,
/// the others and whole leaves ±`band · spacing`. `recorded` is the distance within which
/// the file's field is a distance, when it says.
pub(crate) fn write_vdb(
    path: &Path,
    volume: &CoefficientVolume,
    grid: &Grid,
    band: f32,
    recorded: Option<f32>,
    half: bool,
    compression: VdbCompression,
) -> Result<()> {
    if !(band.is_finite() && band > 0.0 && band <= MAX_VDB_BAND) {
        return Err(Error::parameter(format!(
            "the level set's band must be more than 0 and at most {MAX_VDB_BAND} voxels, \
             got {band}"
        )));
    }
    let background = band * grid.spacing;
    if let Some(recorded) = recorded {
        // Beyond the recorded band the field is a clamp, not a distance.
        if background > recorded * (1.0 + 1e-5) {
            return Err(Error::parameter(format!(
                "a band of {band} voxels ({background} units) reaches beyond the {recorded} \
                 units within which this file's field is a distance; ask for a band of at \
                 most {:.3} voxels, or encode with a wider band",
                recorded / grid.spacing
            ))
            .at(path));
        }
    }
    // Inside leaves are listed too: a fine resampling of a large inside is refused from the
    // source's inside bricks alone, before the count below visits every leaf of the grid.
    crate::memory::check_memory(
        "writing the OpenVDB level set",
        inside_leaves_at_least(volume, grid).saturating_mul(BYTES_PER_VDB_LEAF),
        "lower the resolution or the band",
    )?;
    let leaves = leaf_counts(grid);
    let bounds = LeafBounds::new(volume, grid);
    let candidate = |n: usize| {
        let b = [
            n % leaves[0],
            n / leaves[0] % leaves[1],
            n / (leaves[0] * leaves[1]),
        ];
        (bounds.side(b, background) != Some(Side::Outside)).then(|| origin(b))
    };
    let all = leaves[0] * leaves[1] * leaves[2];
    // Counted before they are listed, so a job too large is refused before it allocates.
    let count = listed_count(&bounds, leaves, background);
    crate::memory::check_memory(
        "writing the OpenVDB level set",
        (count as u64).saturating_mul(BYTES_PER_VDB_LEAF),
        "lower the resolution or the band",
    )?;
    let origins: Vec<VdbLeaf> = (0..all).into_par_iter().filter_map(candidate).collect();
    let world = pgvol_core::frame::to_world(grid.origin, grid.offset);
    let header = LevelSetGrid {
        name: VDB_GRID_NAME,
        transform: UniformScaleTranslate {
            voxel_size: grid.spacing as f64,
            translation: world.to_array(),
        },
        background,
        half,
        compression,
    };
    write_level_set(path, &header, &origins, |o| {
        let b = o.map(|c| c as usize >> LEAF_LOG2);
        match bounds.side(b, background) {
            Some(Side::Outside) => VdbLeafValues::Outside,
            Some(Side::Inside) => VdbLeafValues::Inside,
            None => VdbLeafValues::Sampled(sample_leaf(volume, grid, b)),
        }
    })
    .writing()
}

/// A lower bound on the leaves of `grid` inside the shape: per absent inside brick of the
/// volume, the leaves that fit in its nodes' box shrunk by the two spacings a basis function
/// reaches (so no stored coefficient weighs on them), each in one brick only.
fn inside_leaves_at_least(volume: &CoefficientVolume, grid: &Grid) -> u64 {
    let coeffs = &volume.coeffs;
    let side = (BRICK_EDGE - 1) as f32 - 4.0;
    let per_axis = (side * volume.grid.spacing / (LEAF_EDGE as f32 * grid.spacing)).floor() - 1.0;
    // A NaN ratio (a spacing of zero) bounds nothing.
    if per_axis.is_nan() || per_axis < 1.0 {
        return 0;
    }
    let inside = coeffs
        .all_bricks()
        .filter(|&b| !coeffs.is_stored(b) && coeffs.is_inside(b))
        .count() as u64;
    inside.saturating_mul((per_axis as u64).saturating_pow(3))
}

/// How many leaves of a grid of `leaves` per axis are not outside by `bounds`: those the
/// writer lists. Blocks of leaves on one side are counted whole, so the count follows the
/// surface rather than the grid's volume.
fn listed_count(bounds: &LeafBounds, leaves: [usize; 3], background: f32) -> usize {
    let listed = |b: [usize; 3]| bounds.side(b, background) != Some(Side::Outside);
    let blocks = leaves.map(|n| n.div_ceil(COUNT_BLOCK));
    (0..blocks[0] * blocks[1] * blocks[2])
        .into_par_iter()
        .map(|n| {
            let block = [
                n % blocks[0],
                n / blocks[0] % blocks[1],
                n / (blocks[0] * blocks[1]),
            ];
            let first = block.map(|c| c * COUNT_BLOCK);
            let len: [usize; 3] = std::array::from_fn(|a| COUNT_BLOCK.min(leaves[a] - first[a]));
            match bounds.block_side(first, len, background) {
                Some(Side::Outside) => 0,
                Some(Side::Inside) => len[0] * len[1] * len[2],
                None => (first[2]..first[2] + len[2])
                    .flat_map(|k| (first[1]..first[1] + len[1]).map(move |j| (j, k)))
                    .flat_map(|(j, k)| (first[0]..first[0] + len[0]).map(move |i| [i, j, k]))
                    .filter(|&b| listed(b))
                    .count(),
            }
        })
        .sum()
}

/// Leaves per axis of the blocks the count of leaves decides at once.
const COUNT_BLOCK: usize = 8;

/// Leaves per axis covering `grid`'s nodes.
fn leaf_counts(grid: &Grid) -> [usize; 3] {
    grid.dims.map(|n| n.div_ceil(LEAF_EDGE))
}

fn origin(b: [usize; 3]) -> VdbLeaf {
    b.map(|c| (c * LEAF_EDGE) as i32)
}

/// The field at leaf `b`'s nodes, z fastest; nodes beyond the grid are outside.
fn sample_leaf(volume: &CoefficientVolume, grid: &Grid, b: [usize; 3]) -> Box<[f32; LEAF_VOXELS]> {
    let mut values = Box::new([f32::INFINITY; LEAF_VOXELS]);
    let lo = b.map(|c| c * LEAF_EDGE);
    for x in 0..LEAF_EDGE {
        for y in 0..LEAF_EDGE {
            for z in 0..LEAF_EDGE {
                let [i, j, k] = [lo[0] + x, lo[1] + y, lo[2] + z];
                if i < grid.dims[0] && j < grid.dims[1] && k < grid.dims[2] {
                    values[(x << 6) | (y << 3) | z] = volume.value(grid.point(i, j, k));
                }
            }
        }
    }
    values
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Side {
    Inside,
    Outside,
}

/// Bounds of the field over each leaf from the coefficient bricks that weigh on it.
struct LeafBounds<'a> {
    volume: &'a CoefficientVolume,
    grid: &'a Grid,
    /// `[min, max]` of each coefficient brick (x fastest); empty when the basis gives no
    /// bound (its weights are not a convex combination).
    bricks: Vec<[f32; 2]>,
}

impl<'a> LeafBounds<'a> {
    fn new(volume: &'a CoefficientVolume, grid: &'a Grid) -> Self {
        let coeffs = &volume.coeffs;
        let [bx, by, bz] = coeffs.brick_counts();
        let bricks = if Basis::SEPARABLE.contains(&volume.basis) {
            (0..bx * by * bz)
                .into_par_iter()
                .map(|n| {
                    let b = [n % bx, n / bx % by, n / (bx * by)];
                    match coeffs.brick(b) {
                        None => [coeffs.background_of(b); 2],
                        Some(values) => {
                            // Only the brick's nodes inside the grid count.
                            let (_, size) = coeffs.brick_extent(b);
                            let mut range = [f32::INFINITY, f32::NEG_INFINITY];
                            for k in 0..size[2] {
                                for j in 0..size[1] {
                                    for i in 0..size[0] {
                                        let c = values[pgvol_core::sparse::brick_offset([i, j, k])];
                                        range = [range[0].min(c), range[1].max(c)];
                                    }
                                }
                            }
                            range
                        }
                    }
                })
                .collect()
        } else {
            Vec::new()
        };
        LeafBounds {
            volume,
            grid,
            bricks,
        }
    }

    /// The side of every node of leaf `b` when the field there is at or beyond `background`
    /// in magnitude; `None` when it has to be sampled.
    fn side(&self, b: [usize; 3], background: f32) -> Option<Side> {
        self.block_side(b, [1; 3], background)
    }

    /// [`LeafBounds::side`] for the block of `len` leaves from leaf `first`, all at once.
    fn block_side(&self, first: [usize; 3], len: [usize; 3], background: f32) -> Option<Side> {
        if self.bricks.is_empty() {
            return None;
        }
        let g = &self.volume.grid;
        let lo = first.map(|c| c * LEAF_EDGE);
        let hi: [usize; 3] = std::array::from_fn(|a| {
            ((first[a] + len[a]) * LEAF_EDGE - 1).min(self.grid.dims[a] - 1)
        });
        let (ulo, uhi) = (
            g.to_grid(self.grid.point(lo[0], lo[1], lo[2])),
            g.to_grid(self.grid.point(hi[0], hi[1], hi[2])),
        );
        // Every basis bounded here reaches at most 2 nodes beyond the cell holding a point.
        let nodes: [[usize; 2]; 3] = std::array::from_fn(|a| {
            let n = g.dims[a] as i64;
            [
                (ulo[a].floor() as i64 - 2).clamp(0, n - 1) as usize,
                (uhi[a].ceil() as i64 + 2).clamp(0, n - 1) as usize,
            ]
        });
        // First from the bounds of whole bricks, then, near the surface, from the coefficients
        // themselves: sampling a leaf costs far more than reading its support.
        let [bx, by, _] = self.volume.coeffs.brick_counts();
        let mut range = [f32::INFINITY, f32::NEG_INFINITY];
        for k in nodes[2][0] / BRICK_EDGE..=nodes[2][1] / BRICK_EDGE {
            for j in nodes[1][0] / BRICK_EDGE..=nodes[1][1] / BRICK_EDGE {
                for i in nodes[0][0] / BRICK_EDGE..=nodes[0][1] / BRICK_EDGE {
                    let [lo, hi] = self.bricks[i + bx * (j + by * k)];
                    range = [range[0].min(lo), range[1].max(hi)];
                }
            }
        }
        one_side(range, background).or_else(|| self.gathered_side(nodes, background))
    }

    /// The side of a leaf from the coefficients in its support, `nodes` (first and last
    /// coefficient node per axis).
    fn gathered_side(&self, nodes: [[usize; 2]; 3], background: f32) -> Option<Side> {
        let [[i0, i1], [j0, j1], [k0, k1]] = nodes;
        let mut row = vec![0.0f32; i1 - i0 + 1];
        let mut range = [f32::INFINITY, f32::NEG_INFINITY];
        for k in k0..=k1 {
            for j in j0..=j1 {
                self.volume
                    .coeffs
                    .gather([i0, j, k], [row.len(), 1, 1], &mut row);
                for &c in &row {
                    range = [range[0].min(c), range[1].max(c)];
                }
                if range[0] < background && range[1] > -background {
                    return None;
                }
            }
        }
        one_side(range, background)
    }
}

/// The side of values in `[min, max]` when all are at or beyond `±background`.
fn one_side([min, max]: [f32; 2], background: f32) -> Option<Side> {
    if min >= background {
        Some(Side::Outside)
    } else if max <= -background {
        Some(Side::Inside)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Counting blocks of leaves at once gives the count leaf by leaf, on a sphere resampled
    /// finer than its file and at its own grid, and for bands of one and six voxels.
    #[test]
    fn blocks_count_what_leaves_count() {
        let cube = |n| Grid::cube_res(glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0), n).unwrap();
        let grid = cube(40);
        let [nx, ny, nz] = grid.dims;
        let mut values = Vec::with_capacity(nx * ny * nz);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    values.push(grid.point(i, j, k).length() - 0.6);
                }
            }
        }
        let volume = CoefficientVolume::new(grid, Basis::Bspline3, values).unwrap();
        for target in [grid, cube(301)] {
            let bounds = LeafBounds::new(&volume, &target);
            let leaves = leaf_counts(&target);
            for band in [1.0, 6.0] {
                let background = band * target.spacing;
                let one_by_one = (0..leaves[2])
                    .flat_map(|k| (0..leaves[1]).map(move |j| (j, k)))
                    .flat_map(|(j, k)| (0..leaves[0]).map(move |i| [i, j, k]))
                    .filter(|&b| bounds.side(b, background) != Some(Side::Outside))
                    .count();
                assert!(one_by_one > 0);
                assert_eq!(listed_count(&bounds, leaves, background), one_by_one);
            }
        }
    }
}
