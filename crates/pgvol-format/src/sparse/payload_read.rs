//! Reading a whole `sparse-bricks` payload into the dense coefficient array.
//!
//! Every stored brick is its own blob (one zstd frame) with its own CRC, so bricks decode
//! independently. The dense array is cut into brick layers (`nx · ny · E` consecutive
//! coefficients) and each layer into brick rows (the bricks `(·, bj, bk)`: `E` or fewer grid rows
//! in each of the layer's z-slices), disjoint slices filled in parallel; each value is written
//! exactly once, by the same code whatever the thread count, so the result does not depend on
//! it. A brick row's stored bricks are decoded first, then its grid rows are written in order.
//! Rows are cut one layer at a time, so their bookkeeping stays small next to the array even for
//! thin grids in small bricks.

use std::path::Path;

use pgvol_core::sparse::BrickValues;
use pgvol_core::{Background, SparseGrid, BRICK_EDGE, BRICK_NODES};
use rayon::prelude::*;

use super::brick_read::{background, BrickReader};
use super::index::{bit, layout, Layout};
use crate::dense_alloc::zeroed;
use crate::error::FormatError;
use crate::header::PgvHeader;

/// The coefficients of a sparse payload as a sparse grid: each stored file brick decoded once
/// (in parallel) and cut into the grid's bricks, each unstored one a background of its side.
/// Files whose brick edge is not a multiple of the grid's go through a dense array.
pub(crate) fn decode_payload(
    header: &PgvHeader,
    index: Option<&[u8]>,
    payload: &[u8],
    path: &Path,
) -> Result<SparseGrid, FormatError> {
    let l = layout(header, index, payload, path)?;
    let dims = l.bricks.dims;
    let background = Background::clamp(l.sp.clamp);
    if l.bricks.edge % BRICK_EDGE != 0 {
        let dense = decode_all(&l, path)?;
        return Ok(SparseGrid::from_dense(dims, &dense, background));
    }
    let total = l.bricks.total();
    let stored: Vec<(usize, usize)> = (0..total)
        .filter(|&b| bit(l.stored, b))
        .enumerate()
        .map(|(e, b)| (b, e))
        .collect();
    let mut grid = SparseGrid::new(dims, background);
    for b in (0..total).filter(|&b| !bit(l.stored, b) && bit(l.inside, b)) {
        for (m, _) in grid_bricks_of(&l, b) {
            grid.set_inside(m, true);
        }
    }
    let decoded: Vec<Result<Vec<GridBrick>, FormatError>> = stored
        .par_iter()
        .map_init(
            || (BrickReader::default(), Vec::new()),
            |(reader, values), &(b, e)| {
                let (_, n) = l.bricks.extent(b);
                values.resize(n[0] * n[1] * n[2], 0.0);
                reader.decode(&l, b, e, path, values)?;
                Ok(cut_into_grid_bricks(&l, b, n, values))
            },
        )
        .collect();
    for pieces in decoded {
        for (m, values) in pieces? {
            grid.insert(m, values);
        }
    }
    grid.compact_tiles();
    Ok(grid)
}

/// A grid brick's coordinates and values.
type GridBrick = ([usize; 3], Box<BrickValues>);

/// The grid bricks inside file brick `b`, with their first node relative to the file brick's.
pub(crate) fn grid_bricks_of(
    l: &Layout,
    b: usize,
) -> impl Iterator<Item = ([usize; 3], [usize; 3])> {
    let (lo, n) = l.bricks.extent(b);
    let per = n.map(|c| c.div_ceil(BRICK_EDGE));
    (0..per[2]).flat_map(move |k| {
        (0..per[1]).flat_map(move |j| {
            (0..per[0]).map(move |i| {
                let rel = [i, j, k].map(|c| c * BRICK_EDGE);
                ([0, 1, 2].map(|a| (lo[a] + rel[a]) / BRICK_EDGE), rel)
            })
        })
    })
}

/// File brick `b`'s decoded `values` (`n` nodes, x fastest) as grid bricks; nodes past the
/// grid hold the clamp.
pub(crate) fn cut_into_grid_bricks(
    l: &Layout,
    b: usize,
    n: [usize; 3],
    values: &[f32],
) -> Vec<GridBrick> {
    cut_into_grid_bricks_of(l, b, n, values, l.sp.clamp)
}

/// [`cut_into_grid_bricks`] of any per-node data, nodes past the grid holding `fill`.
pub(crate) fn cut_into_grid_bricks_of<T: Copy>(
    l: &Layout,
    b: usize,
    n: [usize; 3],
    values: &[T],
    fill: T,
) -> Vec<([usize; 3], Box<[T; BRICK_NODES]>)> {
    grid_bricks_of(l, b)
        .map(|(m, rel)| {
            let mut out = Box::new([fill; BRICK_NODES]);
            let len = [0, 1, 2].map(|a| BRICK_EDGE.min(n[a] - rel[a]));
            if len == [BRICK_EDGE; 3] {
                // Rows of a brick edge's fixed length: copies the compiler inlines, where a
                // call per 8-value row cost more than the copy.
                let rows = out.chunks_exact_mut(BRICK_EDGE).enumerate();
                for (row, dst) in rows {
                    let (j, k) = (row % BRICK_EDGE, row / BRICK_EDGE);
                    let src = rel[0] + n[0] * (rel[1] + j + n[1] * (rel[2] + k));
                    let src: &[T; BRICK_EDGE] = values[src..src + BRICK_EDGE]
                        .try_into()
                        .expect("a brick edge");
                    dst.copy_from_slice(src);
                }
                return (m, out);
            }
            for k in 0..len[2] {
                for j in 0..len[1] {
                    let src = rel[0] + n[0] * (rel[1] + j + n[1] * (rel[2] + k));
                    let dst = BRICK_EDGE * (j + BRICK_EDGE * k);
                    out[dst..dst + len[0]].copy_from_slice(&values[src..src + len[0]]);
                }
            }
            (m, out)
        })
        .collect()
}

/// The part of the dense array that brick row `(bj, bk)` covers: in each z-slice of the brick
/// layer, the `nj` grid rows of the brick row (`nj · nx` consecutive coefficients).
pub(crate) struct BrickRow<'a> {
    bj: usize,
    bk: usize,
    /// Index entry of the row's first stored brick.
    first_entry: usize,
    /// One piece per z-slice.
    pieces: Vec<&'a mut [f32]>,
}

/// Index entries before each brick layer: the entry of the layer's first stored brick.
pub(crate) fn layer_first_entries(l: &Layout) -> Vec<usize> {
    let [bx, by, bz] = l.bricks.count;
    let per_layer = bx * by;
    let mut firsts = Vec::with_capacity(bz);
    let mut seen = 0;
    for bk in 0..bz {
        firsts.push(seen);
        seen += (bk * per_layer..(bk + 1) * per_layer)
            .filter(|&b| bit(l.stored, b))
            .count();
    }
    firsts
}

/// Cuts `slab`, the coefficients of brick layer `bk` (x fastest), into its brick rows, disjoint,
/// in brick order; `first_entry` is the index entry of the layer's first stored brick.
pub(crate) fn layer_rows<'a>(
    l: &Layout,
    bk: usize,
    first_entry: usize,
    slab: &'a mut [f32],
) -> Vec<BrickRow<'a>> {
    let [nx, ny, _] = l.bricks.dims;
    let [bx, by, _] = l.bricks.count;
    let edge = l.bricks.edge;
    let mut rows = Vec::with_capacity(by);
    let mut seen = first_entry;
    for bj in 0..by {
        rows.push(BrickRow {
            bj,
            bk,
            first_entry: seen,
            pieces: Vec::with_capacity(edge),
        });
        let first = bx * (bj + by * bk);
        seen += (first..first + bx).filter(|&b| bit(l.stored, b)).count();
    }
    for slice in slab.chunks_mut(nx * ny) {
        for (row, piece) in rows.iter_mut().zip(slice.chunks_mut(nx * edge)) {
            row.pieces.push(piece);
        }
    }
    rows
}

/// A stretch of the grid rows of a brick row: background bricks of one value side by side, or
/// one stored brick.
#[derive(Clone, Copy)]
enum Run {
    Background { x: usize, len: usize, value: f32 },
    Stored { bi: usize },
}

/// Buffers for one brick row, reused: its decoded stored bricks and its runs.
#[derive(Default)]
pub(crate) struct RowScratch {
    bricks: Vec<f32>,
    runs: Vec<Run>,
}

/// Fills a brick row with background values and the stored bricks' values as
/// `decode(b, e, out)` gives them (`e` the index entry).
pub(crate) fn fill_brick_row(
    l: &Layout,
    r: &mut BrickRow,
    scratch: &mut RowScratch,
    mut decode: impl FnMut(usize, usize, &mut [f32]) -> Result<(), FormatError>,
) -> Result<(), FormatError> {
    let [nx, ny, _] = l.bricks.dims;
    let [bx, by, _] = l.bricks.count;
    let edge = l.bricks.edge;
    let cube = edge * edge * edge;
    let first = bx * (r.bj + by * r.bk);
    let nj = edge.min(ny - r.bj * edge);
    let RowScratch { bricks, runs } = scratch;
    bricks.resize(bx * cube, 0.0);
    runs.clear();
    let mut e = r.first_entry;
    for bi in 0..bx {
        let b = first + bi;
        if bit(l.stored, b) {
            let (_, n) = l.bricks.extent(b);
            let count = n[0] * n[1] * n[2];
            decode(b, e, &mut bricks[bi * cube..bi * cube + count])?;
            e += 1;
            runs.push(Run::Stored { bi });
            continue;
        }
        let (value, len) = (background(l, b), edge.min(nx - bi * edge));
        match runs.last_mut() {
            Some(Run::Background {
                len: run, value: v, ..
            }) if v.to_bits() == value.to_bits() => *run += len,
            _ => runs.push(Run::Background {
                x: bi * edge,
                len,
                value,
            }),
        }
    }
    // Whole grid rows, so the dense array is written in order.
    for (kk, piece) in r.pieces.iter_mut().enumerate() {
        for (jj, line) in piece.chunks_exact_mut(nx).enumerate() {
            for run in runs.iter() {
                match *run {
                    Run::Background { x, len, value } => line[x..x + len].fill(value),
                    Run::Stored { bi } => {
                        let ni = edge.min(nx - bi * edge);
                        let src = bi * cube + (kk * nj + jj) * ni;
                        line[bi * edge..bi * edge + ni].copy_from_slice(&bricks[src..src + ni]);
                    }
                }
            }
        }
    }
    Ok(())
}

/// Every coefficient of a checked sparse payload, x fastest, brick rows decoded in parallel.
/// On a damaged file the error is that of the first bad brick in brick order, as a sequential
/// reader would report.
pub(crate) fn decode_all(l: &Layout, path: &Path) -> Result<Vec<f32>, FormatError> {
    let [nx, ny, nz] = l.bricks.dims;
    // Node count is bounded by the container check (MAX_GRID_NODES).
    let mut coeffs = zeroed(nx * ny * nz);
    let firsts = layer_first_entries(l);
    let layers: Vec<Result<(), FormatError>> = coeffs
        .par_chunks_mut(nx * ny * l.bricks.edge)
        .enumerate()
        .map(|(bk, slab)| {
            let rows: Vec<Result<(), FormatError>> = layer_rows(l, bk, firsts[bk], slab)
                .into_par_iter()
                .map_init(
                    || (BrickReader::default(), RowScratch::default()),
                    |(reader, scratch), mut r| {
                        fill_brick_row(l, &mut r, scratch, |b, e, out| {
                            reader.decode(l, b, e, path, out)
                        })
                    },
                )
                .collect();
            rows.into_iter().collect()
        })
        .collect();
    layers.into_iter().collect::<Result<(), _>>()?;
    Ok(coeffs)
}
