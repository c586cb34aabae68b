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
    let count = (0..all)
        .into_par_iter()
        .filter(|&n| candidate(n).is_some())
        .count();
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
        if self.bricks.is_empty() {
            return None;
        }
        let g = &self.volume.grid;
        let lo = b.map(|c| c * LEAF_EDGE);
        let hi: [usize; 3] =
            std::array::from_fn(|a| (lo[a] + LEAF_EDGE - 1).min(self.grid.dims[a] - 1));
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
