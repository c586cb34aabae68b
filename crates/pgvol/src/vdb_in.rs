//! OpenVDB level set → coefficient volume: the grid's voxels are the fit's node samples.
//!
//! pgvol's grid keeps the `.vdb` file's transform, one node at each voxel centre, and is
//! aligned so that each 8³ leaf node of the file is one 8³ brick of the sparse sample grid.
//! The leaves' values (clamped to ±background) fill their bricks, tiles of −background mark
//! the inside bricks, and every other brick is outside; the background is the band. The
//! B-spline interpolation then fits the samples as it fits a mesh's banded distances.

use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use pgvol_core::sparse::{Background, BrickValues, SparseGrid, BRICK_EDGE, BRICK_NODES};
use pgvol_core::Grid;
use pgvol_field::Basis;
use pgvol_format::vdb::read::{read_vdb, VdbLevelSet};
use pgvol_format::PgvFile;

use crate::band::BAND_KEY;
use crate::encode::{fit_failed, fitted_header, Encoded};
use crate::error::{Error, ErrorKind, FileResult, Result};
use crate::memory::{check_memory, BYTES_PER_BAND_BRICK};
use crate::progress::{self, Progress};
use crate::timings::Timings;

/// Bricks of outside samples around the leaves, so the surface stays clear of the grid's
/// edge, where the prefilter mirrors.
const PAD_BRICKS: i64 = 1;

/// How a `.vdb` level set becomes a coefficient volume.
#[derive(Clone, Debug, PartialEq)]
pub struct VdbEncodeOptions {
    /// The grid to read (default: the file's first float level set).
    pub grid_name: Option<String>,
    /// The basis (default the cubic B-spline); its interpolation fits the voxel values.
    pub basis: Basis,
}

impl Default for VdbEncodeOptions {
    fn default() -> Self {
        Self {
            grid_name: None,
            basis: Basis::Bspline3,
        }
    }
}

/// Whether `path` names a `.vdb` file.
pub fn is_vdb(path: impl AsRef<Path>) -> bool {
    path.as_ref()
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("vdb"))
}

/// Encodes the level set of the `.vdb` file at `path` into a `.pgv` file in memory.
pub fn encode_vdb(
    path: impl AsRef<Path>,
    options: &VdbEncodeOptions,
    progress: &dyn Progress,
) -> Result<Encoded> {
    let path = path.as_ref();
    let basis = options.basis;
    if !matches!(basis, Basis::Bspline3 | Basis::Bspline2 | Basis::Trilinear) {
        return Err(Error::parameter(
            "a .vdb level set is fitted by interpolating its voxels, which needs a B-spline or \
             trilinear basis",
        ));
    }
    let start = Instant::now();
    let set = read_vdb(path, options.grid_name.as_deref()).reading()?;
    let name = set.name.clone();
    let band = set.background;
    let (grid, samples) = level_set_samples(set).map_err(|e| e.at(path))?;
    let mut timings = Timings {
        sdf: start.elapsed().as_secs_f64(),
        ..Timings::default()
    };
    let (volume, report) = progress::stage(progress, "fit", |_| {
        pgvol_field::fit::interp_sparse(grid, basis, &samples, pgvol_core::progress::QUIET)
    })?
    .map_err(fit_failed)?;
    timings.fit = report.seconds;
    let mut header = fitted_header(&volume, &report, None);
    header.units = "OpenVDB world units".to_string();
    header.metadata.insert(BAND_KEY.into(), format!("{band}"));
    header.metadata.insert("source_vdb_grid".into(), name);
    Ok(Encoded {
        file: PgvFile { header, volume },
        fit: report,
        sharp: crate::sharp::store::SharpReport::default(),
        timings,
    })
}

/// The grid of `set` (a node per voxel centre over its leaves and a pad) and its samples.
pub(crate) fn level_set_samples(set: VdbLevelSet) -> Result<(Grid, SparseGrid)> {
    let bg = set.background;
    if set.leaves.is_empty() {
        return Err(Error::new(
            ErrorKind::EmptyResult,
            format!(
                "level set '{}' has no leaf node, so no surface: nothing to encode",
                set.name
            ),
        ));
    }
    let edge = BRICK_EDGE as i64;
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for leaf in &set.leaves {
        for a in 0..3 {
            lo[a] = lo[a].min(i64::from(leaf.origin[a]));
            hi[a] = hi[a].max(i64::from(leaf.origin[a]) + edge);
        }
    }
    // Index of node 0: a leaf origin (a multiple of 8) less the pad, so leaves are bricks.
    let first = lo.map(|l| l - PAD_BRICKS * edge);
    let dims = [0, 1, 2].map(|a| (hi[a] + PAD_BRICKS * edge - first[a]) as u128);
    let nodes: u128 = dims.iter().product();
    if nodes > pgvol_core::MAX_GRID_NODES {
        return Err(Error::new(
            ErrorKind::ResourceLimit,
            format!(
                "level set '{}' spans {} x {} x {} voxels, more than the limit of {} grid nodes",
                set.name,
                dims[0],
                dims[1],
                dims[2],
                pgvol_core::MAX_GRID_NODES
            ),
        ));
    }
    let dims = dims.map(|d| d as usize);
    check_memory(
        &format!(
            "encoding the {} leaf nodes of '{}'",
            set.leaves.len(),
            set.name
        ),
        set.leaves.len() as u64 * BYTES_PER_BAND_BRICK,
        "write the level set with a narrower band or a coarser voxel size",
    )?;
    let h = set.voxel_size;
    let origin = [0, 1, 2].map(|a| set.translation[a] + h * first[a] as f64);
    let grid = Grid {
        origin: Vec3::new(origin[0] as f32, origin[1] as f32, origin[2] as f32),
        spacing: h as f32,
        dims,
        offset: Default::default(),
    };
    let mut samples = SparseGrid::new(dims, Background::clamp(bg));
    let brick_counts = samples.brick_counts();
    for tile in set.tiles.iter().filter(|t| t.value < 0.0) {
        // Bricks the tile covers, clipped to the grid.
        let span = 1i64 << tile.log2_edge;
        let range = |a: usize| {
            let start = (i64::from(tile.origin[a]) - first[a])
                .div_euclid(edge)
                .max(0);
            let end = (i64::from(tile.origin[a]) + span - first[a])
                .div_euclid(edge)
                .min(brick_counts[a] as i64);
            start as usize..end.max(start) as usize
        };
        for bz in range(2) {
            for by in range(1) {
                for bx in range(0) {
                    samples.set_inside([bx, by, bz], true);
                }
            }
        }
    }
    let mut negative = false;
    for leaf in set.leaves {
        let b = [0, 1, 2].map(|a| ((i64::from(leaf.origin[a]) - first[a]) / edge) as usize);
        let mut brick: Box<BrickValues> = Box::new([0.0; BRICK_NODES]);
        for (n, &v) in leaf.values.iter().enumerate() {
            // OpenVDB orders a leaf's voxels z fastest, bricks x fastest.
            let (x, y, z) = (n >> 6, (n >> 3) & 7, n & 7);
            brick[x | y << 3 | z << 6] = v.clamp(-bg, bg);
            negative |= v < 0.0;
        }
        samples.insert(b, brick);
    }
    if !negative {
        return Err(Error::new(
            ErrorKind::EmptyResult,
            format!(
                "level set '{}' has no voxel inside (no negative value): nothing to encode",
                set.name
            ),
        ));
    }
    samples.compact_tiles();
    Ok((grid, samples))
}
