//! Surface vertices: one per grid edge whose end values straddle iso, found block by block.
//!
//! Each active block lists the crossings of the edges it owns in node scan order, with a small
//! table per owned node (which of its three edges are crossed and the block-local index of the
//! first), so a cell finds any of its vertices in constant time, also across block borders.

use glam::Vec3;
use rayon::prelude::*;

use crate::blocks::{
    box_index, box_nodes, local_node, origin, Blocks, BoxMasks, BoxValues, BLOCK, BLOCK_NODES,
    BLOCK_SHIFT, BOX_NODES, INACTIVE,
};
use crate::place::onto_edge;
use crate::samples::{Samples, CROSSINGS_PART};
use pgvol_core::progress::{stopped, tick};

/// Callback placing the crossing on the edge from `a` (value `va`) to `b` (value `vb`).
pub(crate) type Refine<'r> = dyn Fn(Vec3, f32, Vec3, f32) -> Vec3 + Sync + 'r;

/// Callback placing the crossing on the edge from `a` (value `va`) to `b` (value `vb`) along
/// `axis` and giving the unit normal there: the position must come from [`onto_edge`].
pub(crate) type PlaceWithNormal<'r> =
    dyn Fn(Vec3, f32, Vec3, f32, usize) -> (Vec3, Vec3) + Sync + 'r;

/// How crossings are placed: positions only, or with unit normals (for dual contouring), which
/// are best taken while the field data around the edge is still in cache.
#[derive(Clone, Copy)]
pub(crate) enum Place<'r> {
    Position(&'r Refine<'r>),
    WithNormal(&'r PlaceWithNormal<'r>),
}

/// The crossing `p` found on the edge from `a` to `b` along `axis`, put onto the edge, and the
/// unit `gradient` there (zero where there is none).
pub(crate) fn with_normal(
    a: Vec3,
    b: Vec3,
    axis: usize,
    p: Vec3,
    gradient: impl Fn(Vec3) -> Vec3,
) -> (Vec3, Vec3) {
    let p = onto_edge(a, b, axis, p);
    (p, gradient(p).normalize_or_zero())
}

/// Bits of a node entry holding its crossed axes; the rest hold the index of its first crossing.
const AXIS_BITS: u32 = 3;

/// Number of axes in a 3-bit set (a table: the baseline x86-64 target has no popcount).
const AXES_COUNT: [u8; 8] = [0, 1, 1, 2, 1, 2, 2, 3];

/// Crossings of the edges owned by one active block.
struct BlockVertices {
    id: u32,
    /// Lowest owned node.
    origin: [usize; 3],
    /// The node values of the box: every value contouring reads after finding the crossings
    /// lies in the box of an active block, so these are the only samples kept.
    values: Box<BoxValues>,
    /// Inside masks of the box, kept for the cell pass.
    masks: BoxMasks,
    /// Per owned node (see [`local_node`]): crossed axes in the low bits, then the block-local
    /// index of the node's first crossing. Indices grow with the node, which `locate` uses.
    node_edges: [u16; BLOCK_NODES],
    /// The block's crossings while they are found; moved into [`Crossings`]' arrays after.
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// How many crossings the block owns.
    count: u32,
}

/// The box of an active block, as the cell passes read it.
#[derive(Clone, Copy)]
pub(crate) struct BlockBox<'a> {
    /// Lowest owned node.
    pub origin: [usize; 3],
    pub values: &'a BoxValues,
    pub masks: &'a BoxMasks,
}

/// Every crossing of the grid, block by block.
pub(crate) struct Crossings {
    pub blocks: Blocks,
    vertices: Vec<BlockVertices>,
    /// Global index of each active block's first crossing.
    base: Vec<u32>,
    /// All positions in global order: active blocks ascending, node scan order within a block.
    pub positions: Vec<Vec3>,
    /// Unit normals at the positions with [`Place::WithNormal`], else empty.
    pub normals: Vec<Vec3>,
}

impl Crossings {
    /// Global index of the vertex on the edge along `axis` from node `n`, which must be crossed.
    #[inline]
    pub fn find(&self, n: [usize; 3], axis: usize) -> u32 {
        let slot = self.blocks.slot_of(n);
        debug_assert_ne!(slot, INACTIVE, "a crossed edge lies in an active block");
        self.find_in(slot as usize, n, axis)
    }

    /// [`Self::find`] with a guess: the active block at `slot`, with lowest owned node `o`, is
    /// tried first (most of a cell's edges belong to the cell's own block).
    #[inline]
    pub fn find_from(&self, slot: usize, o: [usize; 3], n: [usize; 3], axis: usize) -> u32 {
        let offset =
            (n[0].wrapping_sub(o[0])) | (n[1].wrapping_sub(o[1])) | (n[2].wrapping_sub(o[2]));
        if offset < BLOCK {
            self.find_in(slot, n, axis)
        } else {
            self.find(n, axis)
        }
    }

    #[inline]
    fn find_in(&self, slot: usize, n: [usize; 3], axis: usize) -> u32 {
        let entry = u32::from(self.vertices[slot].node_edges[local_node(n)]);
        let axes = entry & ((1 << AXIS_BITS) - 1);
        debug_assert!(axes & (1 << axis) != 0, "edge {n:?} {axis} is not crossed");
        let before = u32::from(AXES_COUNT[(axes & ((1 << axis) - 1)) as usize]);
        self.base[slot] + (entry >> AXIS_BITS) + before
    }

    /// The box of the active block at `slot`.
    pub fn block(&self, slot: usize) -> BlockBox<'_> {
        let v = &self.vertices[slot];
        BlockBox {
            origin: v.origin,
            values: &v.values,
            masks: &v.masks,
        }
    }

    /// The value at node `n`, read from the box of the block owning node `owner`, which must be
    /// active and hold `n` in its box.
    pub fn box_value(&self, owner: [usize; 3], n: [usize; 3]) -> f32 {
        let slot = self.blocks.slot_of(owner);
        debug_assert_ne!(slot, INACTIVE, "node {owner:?} is not in an active block");
        let v = &self.vertices[slot as usize];
        v.values[box_index([0, 1, 2].map(|a| n[a] - v.origin[a]))]
    }

    /// Crossings owned by the active block at `slot`.
    pub fn block_len(&self, slot: usize) -> usize {
        self.vertices[slot].count as usize
    }

    /// The global indices of the crossings owned by the active block at `slot`.
    pub fn block_vertices(&self, slot: usize) -> std::ops::Range<u32> {
        let first = self.base[slot];
        first..first + self.vertices[slot].count
    }

    /// Lower node and axis of the edge holding global vertex `g`.
    pub fn locate(&self, g: u32) -> ([usize; 3], usize) {
        let slot = self.base.partition_point(|&b| b <= g) - 1;
        let local = g - self.base[slot];
        let table = &self.vertices[slot].node_edges;
        // The owner is the last node whose first index is not past `local`: nodes after it
        // start beyond its crossings, nodes before it with the same start have none.
        let node = table.partition_point(|&e| u32::from(e) >> AXIS_BITS <= local) - 1;
        let entry = u32::from(table[node]);
        let mut axes = entry & ((1 << AXIS_BITS) - 1);
        for _ in (entry >> AXIS_BITS)..local {
            axes &= axes - 1;
        }
        let o = self.vertices[slot].origin;
        let m = BLOCK - 1;
        let offset = [
            node & m,
            (node >> BLOCK_SHIFT) & m,
            node >> (2 * BLOCK_SHIFT),
        ];
        (
            [o[0] + offset[0], o[1] + offset[1], o[2] + offset[2]],
            axes.trailing_zeros() as usize,
        )
    }
}

/// Finds and places all crossings, in parallel over the candidate blocks of the source, which
/// are read once each; the order does not depend on the number of threads.
pub(crate) fn all_crossings(samples: &Samples, place: Place, limit: u32) -> Crossings {
    let counts = samples.dims.map(|n| n.div_ceil(BLOCK));
    let candidates = samples.nodes.candidates(samples.iso);
    let counter = samples.counter(0.0, CROSSINGS_PART, candidates.len());
    let vertices: Vec<BlockVertices> = candidates
        .par_iter()
        .filter_map(|&id| {
            if stopped(counter.as_ref()) {
                return None;
            }
            tick(counter.as_ref());
            let o = origin(counts, id);
            let nodes = box_nodes(samples.dims, o);
            let mut values = Box::new([0.0; BOX_NODES]);
            samples.nodes.read_box(o, nodes, &mut values);
            let masks = BoxMasks::new(&values, nodes, samples.iso);
            masks
                .is_mixed()
                .then(|| block_crossings(samples, id, o, values, masks, place))
        })
        .collect::<Vec<_>>();
    // Stopped part way, the crossings found are a partial set whose triangles would look up
    // edges never visited: none are kept, and the caller drops the empty result.
    let mut vertices = if stopped(counter.as_ref()) {
        Vec::new()
    } else {
        vertices
    };
    let blocks = Blocks::new(samples.dims, vertices.iter().map(|v| v.id).collect());
    let mut base = Vec::with_capacity(vertices.len());
    let mut n = 0usize;
    for v in &vertices {
        base.push(n as u32);
        n += v.positions.len();
        assert!(n < limit as usize, "too many vertices");
    }
    let mut positions = Vec::with_capacity(n);
    let with_normals = matches!(place, Place::WithNormal(_));
    let mut normals = Vec::with_capacity(if with_normals { n } else { 0 });
    // Each block's arrays are freed as they are copied, so a run's crossings are not held
    // twice (a large flat face crosses a whole plane of blocks in one run).
    for v in &mut vertices {
        v.count = v.positions.len() as u32;
        positions.extend_from_slice(&std::mem::take(&mut v.positions));
        normals.extend_from_slice(&std::mem::take(&mut v.normals));
    }
    Crossings {
        blocks,
        vertices,
        base,
        positions,
        normals,
    }
}

/// Crossings of the edges owned by block `id`, whose lowest node is `o` and whose box holds
/// `values`. The edges are found with bit operations on the box's inside masks; only crossed
/// ones touch the values again.
fn block_crossings(
    samples: &Samples,
    id: u32,
    o: [usize; 3],
    values: Box<BoxValues>,
    masks: BoxMasks,
    place: Place,
) -> BlockVertices {
    let mut out = BlockVertices {
        id,
        origin: o,
        values,
        masks,
        node_edges: [0; BLOCK_NODES],
        positions: Vec::new(),
        normals: Vec::new(),
        count: 0,
    };
    let nodes = masks.nodes;
    // An edge is owned when its lower node is, and exists when its upper node is in the grid.
    let owned = |a: usize| nodes[a].min(BLOCK);
    let x_edges = (1u16 << (nodes[0] - 1)) - 1;
    // The box's last column belongs to the next block.
    let own_x = (1u16 << owned(0)) - 1;
    let mut local = 0u16;
    let mut at = 0usize;
    for dk in 0..BLOCK {
        for dj in 0..BLOCK {
            if dj >= owned(1) || dk >= owned(2) {
                // Nodes beyond the grid own nothing; their entries keep the starts ascending.
                out.node_edges[at..at + BLOCK].fill(local << AXIS_BITS);
                at += BLOCK;
                continue;
            }
            let m = masks.rows[dk][dj];
            let crossed = [
                (m ^ (m >> 1)) & x_edges,
                if dj + 1 < nodes[1] {
                    m ^ masks.rows[dk][dj + 1]
                } else {
                    0
                },
                if dk + 1 < nodes[2] {
                    m ^ masks.rows[dk + 1][dj]
                } else {
                    0
                },
            ];
            let crossed = crossed.map(|c| c & own_x);
            let any = crossed[0] | crossed[1] | crossed[2];
            if any == 0 {
                out.node_edges[at..at + BLOCK].fill(local << AXIS_BITS);
                at += BLOCK;
                continue;
            }
            for di in 0..BLOCK {
                let axes = (crossed[0] >> di & 1)
                    | (crossed[1] >> di & 1) << 1
                    | (crossed[2] >> di & 1) << 2;
                out.node_edges[at + di] = axes | (local << AXIS_BITS);
                local += u16::from(AXES_COUNT[axes as usize]);
            }
            at += BLOCK;
            let mut todo = any;
            while todo != 0 {
                let di = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let a = [o[0] + di, o[1] + dj, o[2] + dk];
                let va = out.values[box_index([di, dj, dk])];
                for (axis, c) in crossed.iter().enumerate() {
                    if c >> di & 1 == 0 {
                        continue;
                    }
                    let mut b = a;
                    b[axis] += 1;
                    let mut db = [di, dj, dk];
                    db[axis] += 1;
                    let vb = out.values[box_index(db)];
                    let (pa, pb) = (samples.node(a), samples.node(b));
                    match place {
                        Place::Position(refine) => {
                            let p = refine(pa, va, pb, vb);
                            out.positions.push(onto_edge(pa, pb, axis, p));
                        }
                        Place::WithNormal(place) => {
                            let (p, n) = place(pa, va, pb, vb, axis);
                            out.positions.push(p);
                            out.normals.push(n);
                        }
                    }
                }
            }
        }
    }
    out
}
