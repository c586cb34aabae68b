//! The grid split into blocks of nodes, and which of them the surface passes through.
//!
//! Block `b` owns the nodes `BLOCK * b .. BLOCK * (b + 1)` along each axis: the grid edges
//! starting at those nodes and the cells whose lowest node they are. Its *box* adds the next
//! node layer, so it holds both ends of every owned edge and every corner of every owned cell.
//! A block whose box is all inside or all outside owns no crossed edge and no crossed cell, so
//! contouring visits only the others: the *active* blocks.

use rayon::prelude::*;

/// Nodes per block edge. A power of two, so a node's block and offset are a shift and a mask.
pub(crate) const BLOCK: usize = 8;
pub(crate) const BLOCK_SHIFT: u32 = BLOCK.trailing_zeros();
/// Nodes owned by one block.
pub(crate) const BLOCK_NODES: usize = BLOCK * BLOCK * BLOCK;

/// Marks a block that the surface does not pass through.
pub(crate) const INACTIVE: u32 = u32::MAX;

/// Nodes per box edge: a block's own nodes and the first layer of the next block.
pub(crate) const BOX: usize = BLOCK + 1;
/// Nodes in one box.
pub(crate) const BOX_NODES: usize = BOX * BOX * BOX;

/// The values of one block's box: node `lo + (di, dj, dk)` at `di + BOX * (dj + BOX * dk)`.
pub(crate) type BoxValues = [f32; BOX_NODES];

/// Position of box node `(di, dj, dk)` in [`BoxValues`].
#[inline]
pub(crate) fn box_index(d: [usize; 3]) -> usize {
    d[0] + BOX * (d[1] + BOX * d[2])
}

/// Blocks per tile edge of [`SlotMap`].
const TILE: usize = 8;
const TILE_SHIFT: u32 = TILE.trailing_zeros();

/// Position in the active list of each active block, by block coordinates. A table of slots per
/// tile of 8³ blocks that holds an active one, found through a table of tiles: a lookup is two
/// reads, and memory is 4 bytes per 64³ nodes of grid plus 2 KiB per tile the surface
/// crosses, where one slot per block would take 4 bytes per 8³ nodes.
struct SlotMap {
    tile_counts: [usize; 3],
    /// Per tile (x fastest), its index in `tables`, or [`INACTIVE`].
    tiles: Vec<u32>,
    tables: Vec<[u32; TILE * TILE * TILE]>,
}

impl SlotMap {
    fn new(counts: [usize; 3]) -> Self {
        let tile_counts = counts.map(|n| n.div_ceil(TILE));
        Self {
            tile_counts,
            tiles: vec![INACTIVE; tile_counts.iter().product()],
            tables: Vec::new(),
        }
    }

    #[inline]
    fn locate(&self, b: [usize; 3]) -> (usize, usize) {
        let t = b.map(|c| c >> TILE_SHIFT);
        let m = TILE - 1;
        (
            t[0] + self.tile_counts[0] * (t[1] + self.tile_counts[1] * t[2]),
            (b[0] & m) | (b[1] & m) << TILE_SHIFT | (b[2] & m) << (2 * TILE_SHIFT),
        )
    }

    #[inline]
    fn get(&self, b: [usize; 3]) -> u32 {
        let (t, at) = self.locate(b);
        match self.tiles[t] {
            INACTIVE => INACTIVE,
            table => self.tables[table as usize][at],
        }
    }

    fn set(&mut self, b: [usize; 3], slot: u32) {
        let (t, at) = self.locate(b);
        if self.tiles[t] == INACTIVE {
            self.tiles[t] = self.tables.len() as u32;
            self.tables.push([INACTIVE; TILE * TILE * TILE]);
        }
        self.tables[self.tiles[t] as usize][at] = slot;
    }
}

/// The blocks of a grid and the active ones among them.
pub(crate) struct Blocks {
    /// Blocks per axis.
    pub counts: [usize; 3],
    /// Ids (x fastest) of the active blocks, ascending.
    pub active: Vec<u32>,
    slots: SlotMap,
}

impl Blocks {
    /// The blocks of a grid of `dims` nodes with the given active ones (ascending ids).
    pub fn new(dims: [usize; 3], active: Vec<u32>) -> Self {
        let counts = dims.map(|n| n.div_ceil(BLOCK));
        let mut slots = SlotMap::new(counts);
        for (slot, &id) in active.iter().enumerate() {
            slots.set(coords(counts, id), slot as u32);
        }
        Self {
            counts,
            active,
            slots,
        }
    }

    /// Position in [`Self::active`] of the block owning node `n`, or [`INACTIVE`].
    #[inline]
    pub fn slot_of(&self, n: [usize; 3]) -> u32 {
        self.slots.get(n.map(|c| c >> BLOCK_SHIFT))
    }
}

/// Block coordinates of block `id` among `counts` blocks.
#[inline]
pub(crate) fn coords(counts: [usize; 3], id: u32) -> [usize; 3] {
    let id = id as usize;
    let [bx, by, _] = counts;
    [id % bx, (id / bx) % by, id / (bx * by)]
}

/// Lowest owned node of block `id` among `counts` blocks.
#[inline]
pub(crate) fn origin(counts: [usize; 3], id: u32) -> [usize; 3] {
    coords(counts, id).map(|b| b << BLOCK_SHIFT)
}

/// Position of node `n` within its block, x fastest.
#[inline]
pub(crate) fn local_node(n: [usize; 3]) -> usize {
    let m = BLOCK - 1;
    (n[0] & m) | ((n[1] & m) << BLOCK_SHIFT) | ((n[2] & m) << (2 * BLOCK_SHIFT))
}

/// Rows of node values, for [`scan_active`].
pub(crate) trait Rows: Sync {
    /// The values of node row `(j, k)`, read from the source or written into `buf`.
    fn row<'s>(&'s self, j: usize, k: usize, buf: &'s mut Vec<f32>) -> &'s [f32];
}

/// The active blocks of a grid of `dims` nodes, found in one read of every row, in parallel
/// over z layers of blocks.
pub(crate) fn scan_active(dims: [usize; 3], iso: f32, rows: &dyn Rows) -> Vec<u32> {
    let counts = dims.map(|n| n.div_ceil(BLOCK));
    let [bx, by, bz] = counts;
    let layers: Vec<Vec<u32>> = (0..bz)
        .into_par_iter()
        .map(|b| {
            let flags = layer_flags(dims, iso, rows, counts, b);
            let first = b * bx * by;
            (0..bx * by)
                .filter(|&at| flags[at] == BOTH)
                .map(|at| (first + at) as u32)
                .collect()
        })
        .collect();
    layers.concat()
}

/// Flags of a block with both inside and outside nodes in its box.
const BOTH: u8 = 3;

/// Inside/outside flags of the boxes of the blocks in z layer `b`, x fastest. Rows are read
/// whole, so the scan streams through memory.
fn layer_flags(
    dims: [usize; 3],
    iso: f32,
    rows: &dyn Rows,
    counts: [usize; 3],
    b: usize,
) -> Vec<u8> {
    let [nx, ny, nz] = dims;
    let [bx, by, _] = counts;
    let mut flags = vec![0u8; bx * by];
    let mut row_flags = vec![0u8; bx];
    // Inside bits of one row, a byte per BLOCK nodes, plus a spare byte so every block's
    // window of BLOCK + 1 bits spans two bytes.
    let mut bits = vec![0u8; bx + 1];
    let mut buf = Vec::new();
    let z0 = b * BLOCK;
    for k in z0..=(z0 + BLOCK).min(nz - 1) {
        for j in 0..ny {
            inside_bits(rows.row(j, k, &mut buf), iso, &mut bits);
            for (x, f) in row_flags.iter_mut().enumerate() {
                let width = (BLOCK + 1).min(nx - x * BLOCK);
                let full = (1u16 << width) - 1;
                let window = (u16::from(bits[x]) | (u16::from(bits[x + 1]) << BLOCK)) & full;
                *f = u8::from(window != 0) | (u8::from(window != full) << 1);
            }
            // Row j is in the box of y block j / BLOCK, and also of the block below when it is
            // that block's closing layer.
            let mut merge = |y: usize| {
                let dst = &mut flags[y * bx..(y + 1) * bx];
                for (d, s) in dst.iter_mut().zip(&row_flags) {
                    *d |= s;
                }
            };
            merge(j / BLOCK);
            if j % BLOCK == 0 && j > 0 {
                merge(j / BLOCK - 1);
            }
        }
    }
    flags
}

/// Inside bits of `row` into `out`, one byte per BLOCK nodes (bit `i` of byte `x` is node
/// `BLOCK * x + i`); bits past the row's end are zero.
#[inline]
fn inside_bits(row: &[f32], iso: f32, out: &mut [u8]) {
    let chunks = row.chunks_exact(BLOCK);
    let rest = chunks.remainder();
    let mut n = 0;
    for (o, c) in out.iter_mut().zip(chunks) {
        *o = pack8(c.try_into().expect("chunks of BLOCK"), iso);
        n += 1;
    }
    let mut b = 0u8;
    for (i, &v) in rest.iter().enumerate() {
        b |= u8::from(v < iso) << i;
    }
    out[n] = b;
    out[n + 1..].fill(0);
}

/// Inside bits of eight values (NaN is outside).
#[cfg(target_arch = "x86_64")]
#[inline]
fn pack8(c: &[f32; 8], iso: f32) -> u8 {
    use std::arch::x86_64::{_mm_cmplt_ps, _mm_loadu_ps, _mm_movemask_ps, _mm_set1_ps};
    // SAFETY: SSE is part of the x86-64 baseline, and both unaligned loads read within `c`.
    // The compare is ordered: false for NaN, as `v < iso` is.
    let bits = unsafe {
        let t = _mm_set1_ps(iso);
        let lo = _mm_cmplt_ps(_mm_loadu_ps(c.as_ptr()), t);
        let hi = _mm_cmplt_ps(_mm_loadu_ps(c.as_ptr().add(4)), t);
        _mm_movemask_ps(lo) | (_mm_movemask_ps(hi) << 4)
    };
    bits as u8
}

#[cfg(not(target_arch = "x86_64"))]
#[inline]
fn pack8(c: &[f32; 8], iso: f32) -> u8 {
    c.iter()
        .enumerate()
        .fold(0, |b, (i, &v)| b | (u8::from(v < iso) << i))
}

/// Inside flags of the nodes in a block's box, one bit mask per node row.
#[derive(Clone, Copy)]
pub(crate) struct BoxMasks {
    /// Bit `di` of `rows[dk][dj]`: node `origin + (di, dj, dk)` is inside.
    pub rows: [[u16; BLOCK + 1]; BLOCK + 1],
    /// Nodes of the box along each axis that lie in the grid (1 to `BLOCK + 1`).
    pub nodes: [usize; 3],
}

impl BoxMasks {
    /// The masks of box `values` holding `nodes` nodes per axis.
    pub fn new(values: &BoxValues, nodes: [usize; 3], iso: f32) -> Self {
        let mut rows = [[0u16; BLOCK + 1]; BLOCK + 1];
        for (dk, plane) in rows.iter_mut().enumerate().take(nodes[2]) {
            for (dj, mask) in plane.iter_mut().enumerate().take(nodes[1]) {
                let start = box_index([0, dj, dk]);
                let mut bits = [0u8; 3];
                inside_bits(&values[start..start + nodes[0]], iso, &mut bits);
                *mask = u16::from(bits[0]) | (u16::from(bits[1]) << BLOCK);
            }
        }
        Self { rows, nodes }
    }

    /// Whether the box holds nodes on both sides: the block is active.
    pub fn is_mixed(&self) -> bool {
        let full = (1u16 << self.nodes[0]) - 1;
        let rows = self.rows[..self.nodes[2]]
            .iter()
            .flat_map(|plane| &plane[..self.nodes[1]]);
        let (any, all) = rows.fold((0, full), |(any, all), &m| (any | m, all & m));
        any != 0 && all != full
    }
}

/// Nodes of the box of the block with lowest node `o` that lie in a grid of `dims` nodes.
#[inline]
pub(crate) fn box_nodes(dims: [usize; 3], o: [usize; 3]) -> [usize; 3] {
    [0, 1, 2].map(|a| (dims[a] - o[a]).min(BOX))
}
