//! The grid split into blocks of nodes, and which of them the surface passes through.
//!
//! Block `b` owns the nodes `BLOCK * b .. BLOCK * (b + 1)` along each axis: the grid edges
//! starting at those nodes and the cells whose lowest node they are. Its *box* adds the next
//! node layer, so it holds both ends of every owned edge and every corner of every owned cell.
//! A block whose box is all inside or all outside owns no crossed edge and no crossed cell, so
//! contouring visits only the others: the *active* blocks.

use rayon::prelude::*;

use crate::samples::Samples;

/// Nodes per block edge. A power of two, so a node's block and offset are a shift and a mask.
pub(crate) const BLOCK: usize = 8;
pub(crate) const BLOCK_SHIFT: u32 = BLOCK.trailing_zeros();
/// Nodes owned by one block.
pub(crate) const BLOCK_NODES: usize = BLOCK * BLOCK * BLOCK;

/// Marks a block that the surface does not pass through.
pub(crate) const INACTIVE: u32 = u32::MAX;

/// The blocks of a grid and the active ones among them.
pub(crate) struct Blocks {
    /// Blocks along each axis: `ceil(nodes / BLOCK)`.
    pub counts: [usize; 3],
    /// Per block (x fastest), its position in `active`, or [`INACTIVE`].
    pub slot: Vec<u32>,
    /// Ids of the active blocks, ascending.
    pub active: Vec<u32>,
}

impl Blocks {
    /// Lowest owned node of block `id`.
    #[inline]
    pub fn origin(&self, id: u32) -> [usize; 3] {
        let id = id as usize;
        let [bx, by, _] = self.counts;
        [id % bx, (id / bx) % by, id / (bx * by)].map(|b| b << BLOCK_SHIFT)
    }

    /// Id of the block owning node `n`.
    #[inline]
    pub fn id_of(&self, n: [usize; 3]) -> usize {
        let [bx, by, _] = self.counts;
        (n[0] >> BLOCK_SHIFT) + bx * ((n[1] >> BLOCK_SHIFT) + by * (n[2] >> BLOCK_SHIFT))
    }
}

/// Position of node `n` within its block, x fastest.
#[inline]
pub(crate) fn local_node(n: [usize; 3]) -> usize {
    let m = BLOCK - 1;
    (n[0] & m) | ((n[1] & m) << BLOCK_SHIFT) | ((n[2] & m) << (2 * BLOCK_SHIFT))
}

/// Finds the active blocks in one read of the samples, in parallel over z layers of blocks.
pub(crate) fn active_blocks(samples: &Samples) -> Blocks {
    let [nx, ny, nz] = samples.dims;
    let counts = [nx, ny, nz].map(|n| n.div_ceil(BLOCK));
    let [bx, by, bz] = counts;
    let layers: Vec<Vec<u8>> = (0..bz)
        .into_par_iter()
        .map(|b| layer_flags(samples, counts, b))
        .collect();
    let mut slot = vec![INACTIVE; bx * by * bz];
    let mut active = Vec::new();
    for (b, flags) in layers.iter().enumerate() {
        for (at, &f) in flags.iter().enumerate() {
            if f == BOTH {
                let id = b * bx * by + at;
                slot[id] = active.len() as u32;
                active.push(id as u32);
            }
        }
    }
    Blocks {
        counts,
        slot,
        active,
    }
}

/// Flags of a block with both inside and outside nodes in its box.
const BOTH: u8 = 3;

/// Inside/outside flags of the boxes of the blocks in z layer `b`, x fastest. Rows are read
/// whole, so the scan streams through memory.
fn layer_flags(samples: &Samples, counts: [usize; 3], b: usize) -> Vec<u8> {
    let [nx, ny, nz] = samples.dims;
    let [bx, by, _] = counts;
    let mut flags = vec![0u8; bx * by];
    let mut row_flags = vec![0u8; bx];
    // Inside bits of one row, a byte per BLOCK nodes, plus a spare byte so every block's
    // window of BLOCK + 1 bits spans two bytes.
    let mut bits = vec![0u8; bx + 1];
    let z0 = b * BLOCK;
    for k in z0..=(z0 + BLOCK).min(nz - 1) {
        for j in 0..ny {
            let start = samples.index(0, j, k);
            inside_bits(&samples.values[start..start + nx], samples.iso, &mut bits);
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
    /// Reads the box of the block whose lowest node is `o`.
    pub fn read(samples: &Samples, o: [usize; 3]) -> Self {
        let nodes = [0, 1, 2].map(|a| (samples.dims[a] - o[a]).min(BLOCK + 1));
        let mut rows = [[0u16; BLOCK + 1]; BLOCK + 1];
        for (dk, plane) in rows.iter_mut().enumerate().take(nodes[2]) {
            for (dj, mask) in plane.iter_mut().enumerate().take(nodes[1]) {
                let start = samples.index(o[0], o[1] + dj, o[2] + dk);
                let row = &samples.values[start..start + nodes[0]];
                let mut bits = [0u8; 3];
                inside_bits(row, samples.iso, &mut bits);
                *mask = u16::from(bits[0]) | (u16::from(bits[1]) << BLOCK);
            }
        }
        Self { rows, nodes }
    }
}
