//! One layer's 2D grid and its contours: marching squares over the blocks of cells the contour
//! can cross, vertices on the continuous field, loops traced with the inside on their left.
//!
//! The grid's cells are grouped in blocks of [`BLOCK`]². A block whose nodes the field can bound
//! to one side ([`LayerField::side_of`]) holds no crossing and is never evaluated, so a layer
//! costs what its contours' length does, not its area. Nodes, edges and vertices are numbered as
//! in a dense pass over the whole grid, and the loops come out in the same order.

use super::edge_table::EdgeTable;
use crate::SliceError;

/// Most nodes in one layer's 2D grid (a 16384² grid would need 1 GiB per layer in flight).
pub const MAX_LAYER_NODES: usize = 1 << 26;

/// Cells per block edge.
pub(crate) const BLOCK: usize = 8;

/// Vertices keep this fraction of their grid edge from its ends, so no segment touches a node
/// and segments of different cells meet only at shared vertices.
const EDGE_MARGIN: f32 = 1e-3;

/// The field on one layer plane.
pub(crate) trait LayerField {
    /// What sampling a block of nodes keeps for [`LayerField::edge_zero`]; one is reused from
    /// block to block.
    type Block: Default;

    fn value(&self, u: f32, v: f32) -> f32;

    /// Values at the nodes `(us[i], vs[j])` into `out[i + us.len() · j]`, and into `block`
    /// what finding zeros on the edges between them can use. `us[0]` and `vs[0]` are node
    /// `first` of the layer grid.
    fn sample(
        &self,
        _first: [usize; 2],
        us: &[f32],
        vs: &[f32],
        out: &mut [f32],
        _block: &mut Self::Block,
    ) {
        for (j, &v) in vs.iter().enumerate() {
            for (i, &u) in us.iter().enumerate() {
                out[i + us.len() * j] = self.value(u, v);
            }
        }
    }

    /// The zero of the field on the edge from `p` by `step` (one spacing along one axis), whose
    /// ends take the values `ends`: [`edge_root`] of [`LayerField::along`]. `p` is node `node`
    /// (indices into `us` and `vs`) of the block [`LayerField::sample`] kept `block` from, from
    /// which a field may find the zero faster.
    fn edge_zero(
        &self,
        _block: &Self::Block,
        _node: [usize; 2],
        p: [f32; 2],
        step: [f32; 2],
        ends: [f32; 2],
    ) -> f32 {
        edge_root(&*self.along(p, step), ends[0], ends[1])
    }

    /// `Some(inside)` when every point of the rectangle `u × v` is on one side (`value < 0`
    /// inside), `None` when that is not known.
    fn side_of(&self, _u: [f32; 2], _v: [f32; 2]) -> Option<bool> {
        None
    }

    /// The field along the segment from `p` by `step` (along one axis), as a function of the
    /// fraction `t` of the way; the same values as [`LayerField::value`] there.
    fn along<'a>(&'a self, p: [f32; 2], step: [f32; 2]) -> Box<dyn Fn(f32) -> f32 + 'a> {
        Box::new(move |t| self.value(p[0] + step[0] * t, p[1] + step[1] * t))
    }

    /// Rectangles `[[u0, u1], [v0, v1]]` outside which every point of the grid box is on one
    /// side, the same for all of them, or `None` when that is not known.
    fn uncertain(&self) -> Option<Vec<[[f32; 2]; 2]>> {
        None
    }

    /// The rectangle within which [`LayerField::uncertain`] speaks; beyond it, points may take
    /// another side.
    fn known_box(&self) -> [[f32; 2]; 2] {
        [[f32::NEG_INFINITY, f32::INFINITY]; 2]
    }
}

/// A layer's 2D grid: `n[0] × n[1]` nodes at `origin + spacing · (i − 1, j − 1)`, the outer ring
/// artificial.
pub(crate) struct Plane {
    origin: [f32; 2],
    spacing: f32,
    n: [usize; 2],
    /// The nodes' coordinates along each axis ([`Plane::node`]'s), for sampling rows of them.
    coordinates: [Vec<f32>; 2],
}

/// The values of one block's nodes; its buffers are reused from block to block.
#[derive(Default)]
struct BlockNodes<K> {
    /// First node of the block.
    first: [usize; 2],
    /// First node sampled (the block's first not on the ring).
    sampled: [usize; 2],
    /// What sampling kept.
    kept: K,
    /// Nodes per axis (cells + 1).
    len: [usize; 2],
    values: Vec<f32>,
    /// False on the ring and where the field is not finite, whose values are stand-ins (±h)
    /// and whose edges are cut by linear interpolation.
    real: Vec<bool>,
    /// The sampled nodes' values.
    sampled_values: Vec<f32>,
    /// Per node row of `values`, bit i set when node i lies inside.
    inside_rows: Vec<u32>,
}

impl<K> BlockNodes<K> {
    fn at(&self, i: usize, j: usize) -> (f32, bool) {
        let k = i - self.first[0] + self.len[0] * (j - self.first[1]);
        (self.values[k], self.real[k])
    }
}

/// What a layer's contouring did, for measuring how its cost grows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LayerCost {
    /// Grid nodes whose field value was computed.
    pub nodes: u64,
    /// Blocks of cells visited.
    pub blocks: u64,
    /// Grid edges the contours cross.
    pub crossings: u64,
}

impl Plane {
    pub(crate) fn new(u: (f32, f32), v: (f32, f32), spacing: f32) -> Result<Plane, SliceError> {
        let axis = |(lo, hi): (f32, f32)| {
            let cells = ((hi - lo) / spacing).ceil().max(1.0);
            let origin = (lo + hi) * 0.5 - cells * spacing * 0.5;
            (origin, cells as f64 + 3.0)
        };
        let (ou, nu) = axis(u);
        let (ov, nv) = axis(v);
        if nu * nv > MAX_LAYER_NODES as f64 {
            return Err(SliceError::BadParameter(format!(
                "a layer grid of {nu} x {nv} nodes exceeds the limit of {MAX_LAYER_NODES}; \
                 use a coarser resolution"
            )));
        }
        let mut plane = Plane {
            origin: [ou, ov],
            spacing,
            n: [nu as usize, nv as usize],
            coordinates: Default::default(),
        };
        plane.coordinates = [
            (0..plane.n[0]).map(|i| plane.node(i, 0)[0]).collect(),
            (0..plane.n[1]).map(|j| plane.node(0, j)[1]).collect(),
        ];
        Ok(plane)
    }

    /// The coordinates of the nodes along each axis.
    pub(crate) fn node_coordinates(&self) -> [&[f32]; 2] {
        [&self.coordinates[0], &self.coordinates[1]]
    }

    /// Node `i`'s coordinate along axis `k`; node 0 is on the ring of outside nodes.
    fn node_coordinate(&self, k: usize, i: usize) -> f32 {
        self.origin[k] + self.spacing * (i as f32 - 1.0)
    }

    fn node(&self, i: usize, j: usize) -> [f32; 2] {
        [self.node_coordinate(0, i), self.node_coordinate(1, j)]
    }

    /// The blocks that may hold a crossing, in raster order, as (block u, block v): of the
    /// candidates, those whose nodes the field does not place on one side.
    fn active_blocks(&self, field: &impl LayerField) -> Vec<[usize; 2]> {
        self.candidate_blocks(field)
            .into_iter()
            .filter(|&b| {
                let (first, len) = self.block_nodes(b);
                // The real nodes' rectangle; ring nodes are outside.
                let lo = [first[0].max(1), first[1].max(1)];
                let hi = [
                    (first[0] + len[0] - 1).min(self.n[0] - 2),
                    (first[1] + len[1] - 1).min(self.n[1] - 2),
                ];
                let ring = first[0] == 0
                    || first[1] == 0
                    || first[0] + len[0] == self.n[0]
                    || first[1] + len[1] == self.n[1];
                let (a, b) = (self.node(lo[0], lo[1]), self.node(hi[0], hi[1]));
                match field.side_of([a[0], b[0]], [a[1], b[1]]) {
                    Some(inside) => inside && ring,
                    None => true,
                }
            })
            .collect()
    }

    /// Blocks that may hold a crossing, in raster order: every block, or, where the field says
    /// where its sides may change, the blocks meeting those places, the ring or the outside of
    /// the box the field speaks for.
    fn candidate_blocks(&self, field: &impl LayerField) -> Vec<[usize; 2]> {
        let cells = [self.n[0] - 1, self.n[1] - 1];
        let blocks = cells.map(|c| c.div_ceil(BLOCK));
        let every = || {
            (0..blocks[1])
                .flat_map(|bj| (0..blocks[0]).map(move |bi| [bi, bj]))
                .collect()
        };
        let Some(rects) = field.uncertain() else {
            return every();
        };
        // Blocks meeting the node range of [x0, x1] along axis k.
        let range = |k: usize, x: [f32; 2]| -> Option<(usize, usize)> {
            let node = |x: f32| (x - self.origin[k]) / self.spacing + 1.0;
            let (lo, hi) = (node(x[0]).floor(), node(x[1]).ceil());
            if !(lo.is_finite() && hi.is_finite()) {
                return Some((0, blocks[k] - 1));
            }
            if hi < 0.0 || lo > cells[k] as f32 {
                return None;
            }
            let lo = (lo.max(0.0) as usize).saturating_sub(1) / BLOCK;
            let hi = (hi.min(cells[k] as f32) as usize / BLOCK).min(blocks[k] - 1);
            Some((lo, hi))
        };
        // One bit per block: marking and reading them back in raster order costs a word per 64
        // blocks, where sorting the picked blocks took 4 % of a slice.
        let mut picked = vec![0u64; (blocks[0] * blocks[1]).div_ceil(64)];
        let mut add = |u: (usize, usize), v: (usize, usize)| {
            for bj in v.0..=v.1 {
                for b in (u.0..=u.1).map(|bi| bi + blocks[0] * bj) {
                    picked[b / 64] |= 1 << (b % 64);
                }
            }
        };
        for r in &rects {
            if let (Some(u), Some(v)) = (range(0, r[0]), range(1, r[1])) {
                add(u, v);
            }
        }
        // The ring's blocks, but for a side whose real nodes all lie outside: none of its
        // blocks could be active, and asking once spares asking each.
        let last = [blocks[0] - 1, blocks[1] - 1];
        let real = |k: usize, b: (usize, usize)| {
            let first = (b.0 * BLOCK).max(1);
            let end = ((b.1 + 1) * BLOCK).min(self.n[k] - 2);
            [self.node_coordinate(k, first), self.node_coordinate(k, end)]
        };
        let sides = [
            ((0, last[0]), (0, 0)),
            ((0, last[0]), (last[1], last[1])),
            ((0, 0), (0, last[1])),
            ((last[0], last[0]), (0, last[1])),
        ];
        for (u, v) in sides {
            if field.side_of(real(0, u), real(1, v)) != Some(false) {
                add(u, v);
            }
        }
        // Blocks reaching past the field's box.
        let known = field.known_box();
        for k in 0..2 {
            let lo = self.origin[k] - self.spacing;
            let hi = self.origin[k] + self.spacing * (cells[k] as f32 - 1.0);
            let other = (0, last[1 - k]);
            if lo < known[k][0] {
                if let Some(r) = range(k, [lo, known[k][0]]) {
                    if k == 0 {
                        add(r, other)
                    } else {
                        add(other, r)
                    }
                }
            }
            if hi > known[k][1] {
                if let Some(r) = range(k, [known[k][1], hi]) {
                    if k == 0 {
                        add(r, other)
                    } else {
                        add(other, r)
                    }
                }
            }
        }
        let mut out = Vec::new();
        for (w, &word) in picked.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                let b = 64 * w + bits.trailing_zeros() as usize;
                out.push([b % blocks[0], b / blocks[0]]);
                bits &= bits - 1;
            }
        }
        out
    }

    /// First node and node count per axis of block `b`.
    fn block_nodes(&self, b: [usize; 2]) -> ([usize; 2], [usize; 2]) {
        let first = b.map(|c| c * BLOCK);
        let len = [0, 1].map(|a| BLOCK.min(self.n[a] - 1 - first[a]) + 1);
        (first, len)
    }

    /// Block `b`'s node values into `out`.
    fn evaluate<F: LayerField>(
        &self,
        field: &F,
        b: [usize; 2],
        cost: &mut LayerCost,
        out: &mut BlockNodes<F::Block>,
    ) {
        let (first, len) = self.block_nodes(b);
        let h = self.spacing;
        out.values.clear();
        out.values.resize(len[0] * len[1], h);
        out.real.clear();
        out.real.resize(len[0] * len[1], false);
        // The block's real nodes, sampled together.
        let lo = [first[0].max(1), first[1].max(1)];
        let hi = [
            (first[0] + len[0]).min(self.n[0] - 1),
            (first[1] + len[1]).min(self.n[1] - 1),
        ];
        (out.first, out.len, out.sampled) = (first, len, lo);
        if lo[0] < hi[0] && lo[1] < hi[1] {
            let us = &self.coordinates[0][lo[0]..hi[0]];
            let vs = &self.coordinates[1][lo[1]..hi[1]];
            let count = us.len() * vs.len();
            out.sampled_values.resize(count, 0.0);
            field.sample(lo, us, vs, &mut out.sampled_values, &mut out.kept);
            cost.nodes += count as u64;
            let nu = us.len();
            for j in lo[1]..hi[1] {
                for i in lo[0]..hi[0] {
                    let x = out.sampled_values[i - lo[0] + nu * (j - lo[1])];
                    let k = i - first[0] + len[0] * (j - first[1]);
                    if x.is_finite() {
                        out.values[k] = x;
                        out.real[k] = true;
                    } else if x == f32::NEG_INFINITY {
                        out.values[k] = -h;
                    }
                }
            }
        }
    }

    /// The closed loops of `f(u, v) < 0`, inside on the left, in a deterministic order.
    pub(crate) fn contours<F: LayerField>(
        &self,
        field: &F,
        cost: &mut LayerCost,
    ) -> Vec<Vec<[f32; 2]>> {
        let [nu, nv] = self.n;
        let h = self.spacing;
        let active = self.active_blocks(field);
        cost.blocks += active.len() as u64;
        let edge_id = |i: usize, j: usize, dir: usize| 2 * (i + nu * j) + dir;

        // One vertex per crossed edge: edge id 2·node for +u, 2·node + 1 for +v. Each cell
        // places its lower and left edges (and the grid's last column and row their far ones),
        // so every edge of an evaluated cell is placed once.
        let mut crossings: Vec<(usize, [f32; 2])> = Vec::new();
        // Cells whose corners are not all on one side, with their corners' values
        // counter-clockwise from (i, j), for the second pass. Only they hold crossed edges: a
        // crossed edge's ends differ, and they are corners of its cell.
        let mut mixed: Vec<(usize, usize, [f32; 4])> = Vec::new();
        // Each block's crossings are placed as soon as it is sampled, so one block's buffers
        // serve them all.
        let mut b = BlockNodes::default();
        for block in active {
            self.evaluate(field, block, cost, &mut b);
            let cells = [b.len[0] - 1, b.len[1] - 1];
            // Per node row, a bit per node inside: the cells whose corners all lie on one
            // side, most of a block's, are passed over a row of them at a time.
            b.inside_rows.clear();
            b.inside_rows
                .extend(b.values.chunks_exact(b.len[0]).map(|row| {
                    row.iter()
                        .enumerate()
                        .fold(0u32, |m, (i, &x)| m | u32::from(x < 0.0) << i)
                }));
            let row_cells = (1u32 << cells[0]) - 1;
            for cj in 0..cells[1] {
                let row = &b.values[b.len[0] * cj..b.len[0] * (cj + 2)];
                let (lower, upper) = (b.inside_rows[cj], b.inside_rows[cj + 1]);
                let all_in = lower & lower >> 1 & upper & upper >> 1;
                let any_in = lower | lower >> 1 | upper | upper >> 1;
                let mut crossed = any_in & !all_in & row_cells;
                while crossed != 0 {
                    let ci = crossed.trailing_zeros() as usize;
                    crossed &= crossed - 1;
                    let corners = [
                        row[ci],
                        row[ci + 1],
                        row[b.len[0] + ci],
                        row[b.len[0] + ci + 1],
                    ];
                    let (i, j) = (b.first[0] + ci, b.first[1] + cj);
                    mixed.push((i, j, [corners[0], corners[1], corners[3], corners[2]]));
                    let far_u = (i + 2 == nu).then_some((i + 1, j, 1));
                    let far_v = (j + 2 == nv).then_some((i, j + 1, 0));
                    let own = [Some((i, j, 0)), Some((i, j, 1)), far_u, far_v];
                    for (i, j, dir) in own.into_iter().flatten() {
                        let (ib, jb) = if dir == 0 { (i + 1, j) } else { (i, j + 1) };
                        let (va, ra) = b.at(i, j);
                        let (vb, rb) = b.at(ib, jb);
                        if (va < 0.0) == (vb < 0.0) {
                            continue;
                        }
                        let t = if ra && rb {
                            let pa = self.node(i, j);
                            let step = [h * (1 - dir) as f32, h * dir as f32];
                            let node = [i - b.sampled[0], j - b.sampled[1]];
                            field.edge_zero(&b.kept, node, pa, step, [va, vb])
                        } else {
                            va / (va - vb)
                        };
                        let t = t.clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN);
                        let [u, v] = self.node(i, j);
                        let p = if dir == 0 {
                            [u + h * t, v]
                        } else {
                            [u, v + h * t]
                        };
                        crossings.push((edge_id(i, j, dir), p));
                    }
                }
            }
        }
        cost.crossings += crossings.len() as u64;
        let table = EdgeTable::new(crossings.iter().map(|c| c.0));
        let vertex_of = |e: usize| table.vertex(e);

        // Each vertex has exactly one outgoing segment: along a shared edge the counter-clockwise
        // orders of the two cells are opposite, so a crossing starts a segment in one cell and
        // ends one in the other.
        let mut next = vec![u32::MAX; crossings.len()];
        for &(i, j, values) in &mixed {
            let ins = values.map(|x| x < 0.0);
            // Cell edges counter-clockwise: corner k to corner k + 1.
            let edges = [
                edge_id(i, j, 0),
                edge_id(i + 1, j, 1),
                edge_id(i, j + 1, 0),
                edge_id(i, j, 1),
            ];
            let vert = |e: usize| vertex_of(edges[e]);
            let starts = (0..4).filter(|&k| ins[k] && !ins[(k + 1) % 4]);
            let ambiguous = ins[0] == ins[2] && ins[1] == ins[3];
            if ambiguous {
                let v = values.map(|x| x as f64);
                // The bilinear interpolant's saddle; the denominator is non-zero here
                // since the diagonals have opposite signs.
                let saddle = (v[0] * v[2] - v[1] * v[3]) / (v[0] + v[2] - v[1] - v[3]);
                // Inside joined through the centre: each start meets the next edge;
                // otherwise the previous one, cutting off the inside corner.
                let turn = if saddle < 0.0 { 1 } else { 3 };
                for k in starts {
                    next[vert(k) as usize] = vert((k + turn) % 4);
                }
            } else {
                let end = (0..4).find(|&k| !ins[k] && ins[(k + 1) % 4]);
                if let (Some(k), Some(e)) = (starts.into_iter().next(), end) {
                    next[vert(k) as usize] = vert(e);
                }
            }
        }

        // Each loop starts at its crossing of least edge id, and the loops come in the order of
        // those ids: the numbering of a dense pass over the grid, whatever order the blocks
        // were visited in.
        let mut seen = vec![false; crossings.len()];
        let mut loops: Vec<(usize, Vec<[f32; 2]>)> = Vec::new();
        for s in 0..crossings.len() {
            if seen[s] {
                continue;
            }
            let mut ids = Vec::new();
            let mut k = s;
            while !seen[k] {
                seen[k] = true;
                ids.push(k);
                k = next[k] as usize;
            }
            let first = (0..ids.len())
                .min_by_key(|&i| crossings[ids[i]].0)
                .unwrap_or(0);
            ids.rotate_left(first);
            let points = ids.iter().map(|&k| crossings[k].1).collect();
            loops.push((crossings[ids[0]].0, points));
        }
        loops.sort_unstable_by_key(|l| l.0);
        loops.into_iter().map(|l| l.1).collect()
    }
}

/// Root finding along an edge ends when its estimate moves less than this fraction of the edge:
/// far below the simplification tolerance (a tenth of a spacing by default).
const ROOT_STEP: f32 = 1e-5;

/// The zero of `g` on [0, 1] given `g(0) = va`, `g(1) = vb` of opposite signs: regula falsi with
/// the Illinois modification, which keeps the bracket and converges superlinearly. It stops once
/// an estimate moves less than [`ROOT_STEP`] of the edge. Generic, so that a polynomial `g` is
/// compiled into it rather than called.
pub(crate) fn edge_root<G: Fn(f32) -> f32 + ?Sized>(g: &G, va: f32, vb: f32) -> f32 {
    let (mut t0, mut f0, mut t1, mut f1) = (0.0f32, va, 1.0f32, vb);
    let mut side = 0i8;
    let mut t = f0 / (f0 - f1);
    let mut last = f32::NAN;
    for _ in 0..12 {
        t = t0 - f0 * (t1 - t0) / (f1 - f0);
        if !t.is_finite() {
            return 0.5 * (t0 + t1);
        }
        if (t - last).abs() < ROOT_STEP {
            break;
        }
        last = t;
        let ft = g(t);
        if ft == 0.0 || (t1 - t0) < 1e-6 || !ft.is_finite() {
            break;
        }
        if (ft < 0.0) == (f1 < 0.0) {
            t1 = t;
            f1 = ft;
            if side == -1 {
                f0 *= 0.5;
            }
            side = -1;
        } else {
            t0 = t;
            f0 = ft;
            if side == 1 {
                f1 *= 0.5;
            }
            side = 1;
        }
    }
    t
}
