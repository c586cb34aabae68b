//! Sampling a coefficient volume only where the level set can pass.
//!
//! The bricks of sampling nodes whose supporting coefficients lie on one side of iso (see
//! `support`) need no evaluation: their nodes take the coefficients' bound, which keeps every
//! sign and so every crossing of the level set. For the supports that reach only absent
//! coefficient bricks that decision takes a few byte operations per brick.
//!
//! Contouring then reads only the boxes of the blocks that may hold both sides, so what is kept
//! is the evaluated bricks, the bounds of the skipped bricks next to those blocks, and two bytes
//! per brick while the blocks are found.

use std::collections::HashMap;
use std::ops::Range;

use pgvol_core::sparse::{brick_offset, BrickValues};
use pgvol_core::{Background, SparseGrid, BRICK_EDGE, BRICK_NODES};
use pgvol_field::{CoefficientVolume, Grid};
use rayon::prelude::*;

use pgvol_core::progress::{stopped, tick, Span};

use crate::cubic_eval::bspline3_value_gradient;

use crate::blocks::{box_index, BoxValues, BLOCK};
use crate::samples::Nodes;
use crate::support::{
    background_bound, coefficient_ranges, gathered_bound, support_kinds, support_side, STORED,
};
use crate::window_or::or_over_boxes;

// A box of 9 nodes from any node reaches at most two bricks per axis.
const _: () = assert!(BRICK_EDGE == BLOCK);

/// Sides a brick's nodes may lie on: bit set of these.
const INSIDE: u8 = 1;
const OUTSIDE: u8 = 2;
const BOTH: u8 = INSIDE | OUTSIDE;

/// The field of a coefficient volume on a grid, surrounded by one layer of outside padding as
/// `contour_volume` contours it, evaluated only in the bricks (of [`BRICK_EDGE`]³ nodes of the
/// sampling grid) the level set may cross.
///
/// Node `(i, j, k)` of this source is node `(i - 1, j - 1, k - 1)` of the sampling grid. A
/// contour block's box spans at most two bricks per axis, because both are 8 nodes wide.
pub(crate) struct VolumeNodes {
    /// Nodes of the sampling grid per axis.
    inner: [usize; 3],
    brick_counts: [usize; 3],
    pad: f32,
    /// Field values of the evaluated bricks that a candidate block may read.
    exact: SparseGrid,
    /// The value of every node of the skipped bricks next to a candidate block, by brick id.
    bounds: HashMap<usize, f32>,
    candidates: Vec<u32>,
}

/// What a brick's nodes hold when read.
#[derive(Clone, Copy)]
enum Fill<'a> {
    Values(&'a BrickValues),
    Bound(f32),
}

impl VolumeNodes {
    /// The field of `volume` on `grid`, padded with `iso + spacing`: bricks are sorted into
    /// evaluated and bounded ones in one parallel pass, then the contour blocks whose box may
    /// hold both sides are found from the bricks' sides.
    ///
    /// Rows of bricks done are reported through `span`.
    pub fn new(volume: &CoefficientVolume, grid: &Grid, iso: f32, span: Option<Span>) -> Self {
        Self::layers(volume, grid, iso, [0, grid.dims[2] + 1], span)
    }

    /// [`Self::new`] for the padded node layers `layers[0]..=layers[1]` alone: only the bricks
    /// holding them are sorted and evaluated, and only the blocks owning one of them (their
    /// boxes cut at those layers) are candidates. Nodes outside the layers must not be read.
    pub fn layers(
        volume: &CoefficientVolume,
        grid: &Grid,
        iso: f32,
        layers: [usize; 2],
        span: Option<Span>,
    ) -> Self {
        let zb = sorted_bricks(grid.dims[2], layers);
        let sampler = Sampler::new(volume, grid, iso, zb.clone());
        let brick_counts = sampler.brick_counts;
        let [bx, by, _] = brick_counts;
        let counter = span.map(|s| s.counter(by * zb.len()));
        let rows: Vec<Row> = (0..by * zb.len())
            .into_par_iter()
            .map(|r| {
                // Stopped: the rows not yet begun read as outside (no crossing), and the
                // caller drops the result.
                if stopped(counter.as_ref()) {
                    return Row {
                        sides: vec![OUTSIDE; bx],
                        exact: Vec::new(),
                    };
                }
                tick(counter.as_ref());
                sampler.row(r)
            })
            .collect();
        let mut exact = SparseGrid::new(grid.dims, Background::clamp(0.0));
        let mut sides = Vec::with_capacity(bx * by * zb.len());
        for (r, row) in rows.into_iter().enumerate() {
            sides.extend_from_slice(&row.sides);
            for (bi, values) in row.exact {
                exact.insert([bi, r % by, zb.start + r / by], values);
            }
        }
        let reach = Reach {
            inner: grid.dims,
            brick_counts,
            layers,
            bricks: zb,
        };
        let (candidates, touched) = candidate_blocks(&reach, &sides, &exact);
        drop(sides);
        let brick = |id: usize| [id % bx, (id / bx) % by, id / (bx * by)];
        let fills: Vec<(usize, Option<f32>)> = touched
            .par_iter()
            .map(|&id| (id, sampler.bound(brick(id))))
            .collect();
        let mut bounds = HashMap::new();
        for (id, bound) in fills {
            match bound {
                Some(bound) => {
                    bounds.insert(id, bound);
                }
                // Bricks without a bound not kept when sorted: evaluated again, as few as the
                // blocks next to the surface need.
                None => exact.insert(brick(id), sampler.evaluate(brick(id))),
            }
        }
        Self {
            inner: grid.dims,
            brick_counts,
            pad: iso + grid.spacing,
            exact,
            bounds,
            candidates,
        }
    }

    /// What the nodes of brick `b` hold; the brick must be evaluated or next to a candidate.
    fn fill(&self, b: [usize; 3]) -> Fill<'_> {
        match self.exact.brick(b) {
            Some(values) => Fill::Values(values),
            None => {
                let [bx, by, _] = self.brick_counts;
                let id = b[0] + bx * (b[1] + by * b[2]);
                Fill::Bound(self.bounds[&id])
            }
        }
    }
}

/// The brick layers along z holding the padded node layers `layers[0]..=layers[1]` of a
/// sampling grid of `nz` layers (padded layer `k` is sampling layer `k - 1`; the padding
/// itself needs no brick).
fn sorted_bricks(nz: usize, layers: [usize; 2]) -> Range<usize> {
    let (first, last) = (layers[0].max(1) - 1, layers[1].min(nz).max(1) - 1);
    first / BRICK_EDGE..last / BRICK_EDGE + 1
}

/// The first and last coefficient layer along z of a volume on `volume_grid` that
/// [`VolumeNodes::layers`] on `grid` reads for the padded node `layers`.
pub(crate) fn coefficient_layers(
    volume_grid: &Grid,
    grid: &Grid,
    layers: [usize; 2],
) -> [usize; 2] {
    let bricks = sorted_bricks(grid.dims[2], layers);
    let first = bricks.start * BRICK_EDGE;
    let last = (bricks.end * BRICK_EDGE).min(grid.dims[2]) - 1;
    coefficient_ranges(volume_grid, grid.point(0, 0, first), grid.point(0, 0, last))[2]
}

/// The sides of one row of bricks, and the values of those evaluated and kept.
struct Row {
    sides: Vec<u8>,
    exact: Vec<(usize, Box<BrickValues>)>,
}

/// Sorts the bricks of a sampling grid into bounded and evaluated ones.
struct Sampler<'a> {
    volume: &'a CoefficientVolume,
    grid: &'a Grid,
    iso: f32,
    brick_counts: [usize; 3],
    /// The brick layers along z being sorted.
    layers: Range<usize>,
    /// Per axis and brick index (along z, from `layers.start`): the coefficient nodes that can
    /// weigh on its nodes.
    ranges: [Vec<[usize; 2]>; 3],
    /// Per brick, the kinds of the coefficient bricks its nodes' support reaches; empty for
    /// bases whose values are not convex combinations of their coefficients.
    supports: Vec<u8>,
    /// Whether the nodes are the volume's own with a separable basis, where evaluating a brick
    /// (a 3-tap blur of its coefficients) costs less than bounding its support.
    on_own_grid: bool,
    /// The volume node of the grid's first node, when every node of the grid is one of the
    /// volume's (a box of them).
    first_volume_node: Option<[usize; 3]>,
}

/// The node of `volume`'s grid at `grid`'s first node when `grid` is a box of `volume`'s nodes:
/// the same spacing and frame, its origin a node of `volume` to a thousandth of a spacing, and
/// its far corner inside `volume`'s grid.
fn volume_node_of(volume: &Grid, grid: &Grid) -> Option<[usize; 3]> {
    if grid.spacing != volume.spacing || grid.offset != volume.offset {
        return None;
    }
    let at = (grid.origin - volume.origin) / volume.spacing;
    let first = at.round();
    if (at - first).abs().max_element() > 1e-3 || first.min_element() < 0.0 {
        return None;
    }
    let first = first.to_array().map(|c| c as usize);
    (0..3)
        .all(|a| first[a] + grid.dims[a] <= volume.dims[a])
        .then_some(first)
}

impl<'a> Sampler<'a> {
    fn new(volume: &'a CoefficientVolume, grid: &'a Grid, iso: f32, layers: Range<usize>) -> Self {
        let brick_counts = grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
        // Points differing only off axis `a` give the same range along it.
        let ranges = [0, 1, 2].map(|a| -> Vec<[usize; 2]> {
            let bricks = if a == 2 {
                layers.clone()
            } else {
                0..brick_counts[a]
            };
            bricks
                .map(|b| {
                    let first = b * BRICK_EDGE;
                    let last = (first + BRICK_EDGE).min(grid.dims[a]) - 1;
                    let lo = grid.point(first, first, first);
                    let hi = grid.point(last, last, last);
                    coefficient_ranges(&volume.grid, lo, hi)[a]
                })
                .collect()
        });
        let supports = if volume.basis.is_separable() {
            support_kinds(&volume.coeffs, [&ranges[0], &ranges[1], &ranges[2]], iso)
        } else {
            Vec::new()
        };
        Self {
            volume,
            grid,
            iso,
            brick_counts,
            layers,
            ranges,
            supports,
            on_own_grid: volume_node_of(&volume.grid, grid).is_some()
                && volume.basis.is_separable(),
            first_volume_node: volume_node_of(&volume.grid, grid),
        }
    }

    /// The bound of every node of brick `b` when all lie on one side of iso: from the sides of
    /// the absent coefficient bricks its support reaches, else from the coefficients.
    fn bound(&self, b: [usize; 3]) -> Option<f32> {
        let [bx, by, _] = self.brick_counts;
        let z = b[2] - self.layers.start;
        let kinds = *self.supports.get(b[0] + bx * (b[1] + by * z))?;
        if kinds & STORED == 0 {
            background_bound(self.volume.coeffs.background(), kinds, self.iso)
        } else if self.on_own_grid {
            None
        } else {
            let at = [b[0], b[1], z];
            let ranges = [0, 1, 2].map(|a| self.ranges[a][at[a]]);
            gathered_bound(self.volume, ranges, self.iso)
        }
    }

    /// Whether every node of brick `b` lies above iso (`Some(true)`) or below it, from the
    /// kinds of the coefficient bricks its support reaches.
    fn support_side(&self, b: [usize; 3]) -> Option<bool> {
        let [bx, by, _] = self.brick_counts;
        let z = b[2] - self.layers.start;
        let kinds = *self.supports.get(b[0] + bx * (b[1] + by * z))?;
        support_side(self.volume.coeffs.background(), kinds, self.iso)
    }

    /// Sides of the bricks of row `r` (`bj + by * bk`), evaluating those without a bound. A
    /// one-sided brick without a bound is not kept: it is evaluated again if a block next to
    /// the surface needs it.
    fn row(&self, r: usize) -> Row {
        let [bx, by, _] = self.brick_counts;
        let mut row = Row {
            sides: Vec::with_capacity(bx),
            exact: Vec::new(),
        };
        for bi in 0..bx {
            let b = [bi, r % by, self.layers.start + r / by];
            if let Some(bound) = self.bound(b) {
                row.sides.push(side(bound, self.iso));
                continue;
            }
            // Coefficients all on one side: so are the nodes, whose values are needed only if
            // a block next to the surface reads them (then evaluated, as bricks without a
            // bound are).
            if let Some(above) = self.support_side(b) {
                row.sides.push(if above { OUTSIDE } else { INSIDE });
                continue;
            }
            let values = self.evaluate(b);
            let sides = value_sides(&values, self.grid, b, self.iso);
            row.sides.push(sides);
            if sides == BOTH || !self.supports.is_empty() {
                row.exact.push((bi, values));
            }
        }
        row
    }

    /// The field at the nodes of brick `b` (nodes past the grid's end left 0). On the volume's
    /// own grid a separable basis at the nodes is a 3-tap blur of the coefficients (a tenth of
    /// the work of a stencil per node); the cubic B-spline elsewhere takes its 4³ fast path.
    fn evaluate(&self, b: [usize; 3]) -> Box<BrickValues> {
        let (lo, n) = brick_extent(self.grid, b);
        let mut out = Box::new([0.0; BRICK_NODES]);
        // The volume's own grid, or a box of it starting on a brick corner: each brick is one
        // of the volume's.
        let own_brick = self
            .first_volume_node
            .filter(|f| f.iter().all(|c| c % BRICK_EDGE == 0) && self.volume.basis.is_separable())
            .map(|f| [0, 1, 2].map(|a| b[a] + f[a] / BRICK_EDGE));
        if let Some(b) = own_brick.filter(|_| n == [BRICK_EDGE; 3]) {
            pgvol_field::fit::brick_node_values_into(self.volume, b, &mut out);
            return out;
        }
        if let Some(b) = own_brick {
            let values = pgvol_field::fit::brick_node_values(self.volume, b);
            for k in 0..n[2] {
                for j in 0..n[1] {
                    let at = BRICK_EDGE * (j + BRICK_EDGE * k);
                    out[at..at + n[0]].copy_from_slice(&values[at..at + n[0]]);
                }
            }
            return out;
        }
        if let Some(first) = self
            .first_volume_node
            .filter(|_| self.volume.basis.is_separable())
        {
            // A grid on the volume's own nodes (a box of them): the nodes' values from the
            // coefficients around them, as on the whole grid, not by evaluating the basis.
            let lo = [0, 1, 2].map(|a| first[a] + lo[a]);
            pgvol_field::fit::box_node_values_into(self.volume, lo, n, &mut out);
            return out;
        }
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let p = self.grid.point(lo[0] + i, lo[1] + j, lo[2] + k);
                    let value = match bspline3_value_gradient(self.volume, p) {
                        Some((v, _)) => v,
                        None => self.volume.value(p),
                    };
                    out[i + BRICK_EDGE * (j + BRICK_EDGE * k)] = value;
                }
            }
        }
        out
    }
}

impl Nodes for VolumeNodes {
    fn dims(&self) -> [usize; 3] {
        self.inner.map(|n| n + 2)
    }

    fn candidates(&self, _iso: f32) -> Vec<u32> {
        self.candidates.clone()
    }

    fn read_box(&self, lo: [usize; 3], n: [usize; 3], out: &mut BoxValues) {
        let [nx, ny, nz] = self.inner;
        // The box spans at most two bricks per axis from the one holding its first inner node.
        let first = lo.map(|c| (c.max(1) - 1) / BRICK_EDGE);
        let mut fills: [Option<Fill>; 8] = [None; 8];
        for dk in 0..n[2] {
            for dj in 0..n[1] {
                let row = &mut out[box_index([0, dj, dk])..][..n[0]];
                let (j, k) = (lo[1] + dj, lo[2] + dk);
                if j == 0 || k == 0 || j > ny || k > nz {
                    row.fill(self.pad);
                    continue;
                }
                let (j, k) = (j - 1, k - 1);
                let mut di = 0;
                while di < n[0] {
                    let i = lo[0] + di;
                    if i == 0 || i > nx {
                        row[di] = self.pad;
                        di += 1;
                        continue;
                    }
                    let i = i - 1;
                    let run = (BRICK_EDGE - i % BRICK_EDGE).min(n[0] - di).min(nx - i);
                    let b = [i, j, k].map(|c| c / BRICK_EDGE);
                    let at = (b[0] - first[0]) | (b[1] - first[1]) << 1 | (b[2] - first[2]) << 2;
                    let dst = &mut row[di..di + run];
                    match *fills[at].get_or_insert_with(|| self.fill(b)) {
                        Fill::Values(v) => {
                            let s = brick_offset([i, j, k]);
                            dst.copy_from_slice(&v[s..s + run]);
                        }
                        Fill::Bound(bound) => dst.fill(bound),
                    }
                    di += run;
                }
            }
        }
    }
}

/// The side of a node holding `value`: inside below iso, NaN outside.
fn side(value: f32, iso: f32) -> u8 {
    if value < iso {
        INSIDE
    } else {
        OUTSIDE
    }
}

/// Sides of the nodes of brick `b` of `grid` holding `values`.
fn value_sides(values: &BrickValues, grid: &Grid, b: [usize; 3], iso: f32) -> u8 {
    let (_, n) = brick_extent(grid, b);
    let mut sides = 0;
    for k in 0..n[2] {
        for j in 0..n[1] {
            let at = BRICK_EDGE * (j + BRICK_EDGE * k);
            for &v in &values[at..at + n[0]] {
                sides |= side(v, iso);
            }
        }
    }
    sides
}

/// First node and node counts of brick `b` within `grid`.
fn brick_extent(grid: &Grid, b: [usize; 3]) -> ([usize; 3], [usize; 3]) {
    let lo = b.map(|c| c * BRICK_EDGE);
    let n = [0, 1, 2].map(|a| (lo[a] + BRICK_EDGE).min(grid.dims[a]) - lo[a]);
    (lo, n)
}

/// Which node layers a [`VolumeNodes`] holds, and the bricks it sorted.
struct Reach {
    /// Nodes of the sampling grid per axis.
    inner: [usize; 3],
    brick_counts: [usize; 3],
    /// First and last padded node layer along z.
    layers: [usize; 2],
    /// Brick layers along z sorted (their sides are given from `bricks.start`).
    bricks: Range<usize>,
}

/// The blocks of the padded grid owning one of `reach`'s node layers whose box (cut at those
/// layers) may hold both sides, ascending, and the ids of the bricks their boxes reach that
/// were not evaluated, ascending. `sides` holds a brick's sides for the bricks sorted.
///
/// Contour block `c` owns padded nodes from `BLOCK * c`, inner nodes from `BLOCK * c - 1`, so
/// its box reaches bricks `c - 1` and `c` along each axis, and the padding at the grid's ends.
fn candidate_blocks(reach: &Reach, sides: &[u8], exact: &SparseGrid) -> (Vec<u32>, Vec<usize>) {
    let inner = reach.inner;
    let counts = inner.map(|n| (n + 2).div_ceil(BLOCK));
    let [z0, z1] = reach.layers;
    let first_layer = z0 / BLOCK;
    let block_layers = first_layer..z1 / BLOCK + 1;
    // Per axis and block: the bricks its box reaches, and whether it reaches the padding. Along
    // z the box is cut at the layers held, and bricks count from the first sorted.
    let reach_along = |a: usize, blocks: Range<usize>, cut: [usize; 2], shift: usize| {
        let n = inner[a];
        blocks
            .map(|c| {
                let (lo, hi) = ((BLOCK * c).max(cut[0]), (BLOCK * c + BLOCK).min(cut[1]));
                let (first, last) = (lo.max(1), hi.min(n));
                let bricks = if first <= last {
                    (first - 1) / BRICK_EDGE - shift..(last - 1) / BRICK_EDGE + 1 - shift
                } else {
                    0..0
                };
                (bricks, lo == 0 || hi > n)
            })
            .unzip::<_, _, Vec<Range<usize>>, Vec<bool>>()
    };
    let whole = |a: usize| [0, inner[a] + 1];
    let (xs, xpad) = reach_along(0, 0..counts[0], whole(0), 0);
    let (ys, ypad) = reach_along(1, 0..counts[1], whole(1), 0);
    let (zs, zpad) = reach_along(2, block_layers, reach.layers, reach.bricks.start);
    let [bx, by, _] = reach.brick_counts;
    let reached = or_over_boxes(sides, [bx, by, reach.bricks.len()], [&xs, &ys, &zs]);
    let layers: Vec<Vec<u32>> = reached
        .par_chunks(counts[0] * counts[1])
        .enumerate()
        .map(|(cz, layer)| {
            let first = (first_layer + cz) * counts[0] * counts[1];
            layer
                .iter()
                .enumerate()
                .filter(|&(at, &s)| {
                    let pad = zpad[cz] || ypad[at / counts[0]] || xpad[at % counts[0]];
                    s | if pad { OUTSIDE } else { 0 } == BOTH
                })
                .map(|(at, _)| (first + at) as u32)
                .collect()
        })
        .collect();
    let candidates = layers.concat();
    let shift = reach.bricks.start;
    let mut touched: Vec<usize> = candidates
        .iter()
        .flat_map(|&id| {
            let c = crate::blocks::coords(counts, id);
            let zs = zs[c[2] - first_layer].clone();
            let (xs, ys) = (xs[c[0]].clone(), ys[c[1]].clone());
            zs.flat_map(move |k| {
                let xs = xs.clone();
                ys.clone()
                    .flat_map(move |j| xs.clone().map(move |i| [i, j, k + shift]))
            })
        })
        .filter(|&b| !exact.is_stored(b))
        .map(|b| b[0] + bx * (b[1] + by * b[2]))
        .collect();
    touched.sort_unstable();
    touched.dedup();
    (candidates, touched)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blocks::{box_nodes, origin, BOX_NODES};
    use crate::samples::PaddedNodes;
    use crate::test_volumes::two_balls;
    use pgvol_field::Basis;

    #[test]
    fn a_box_of_the_volumes_nodes_takes_their_values_from_the_coefficients() {
        let v = two_balls(Basis::Bspline3);
        let g = v.grid;
        let first = [5usize, 7, 3];
        let sub = Grid {
            origin: g.origin + glam::Vec3::new(5.0, 7.0, 3.0) * g.spacing,
            dims: [21, 19, 25],
            ..g
        };
        assert_eq!(volume_node_of(&g, &sub), Some(first));
        // Off the nodes, at another spacing or past the grid: sampled as any grid.
        let off = Grid {
            origin: sub.origin + glam::Vec3::splat(0.5 * g.spacing),
            ..sub
        };
        assert_eq!(volume_node_of(&g, &off), None);
        let finer = Grid {
            spacing: 0.5 * g.spacing,
            ..sub
        };
        assert_eq!(volume_node_of(&g, &finer), None);
        let past = Grid {
            dims: [40, 19, 25],
            ..sub
        };
        assert_eq!(volume_node_of(&g, &past), None);
        let whole = pgvol_field::fit::node_values_sparse(&v);
        let sampler = Sampler::new(&v, &sub, 0.0, 0..sub.dims[2].div_ceil(BRICK_EDGE));
        for b in [[0, 0, 0], [1, 2, 1], [2, 2, 3]] {
            let values = sampler.evaluate(b);
            let (lo, n) = brick_extent(&sub, b);
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        let node = [lo[0] + i, lo[1] + j, lo[2] + k];
                        let want = whole.get([0, 1, 2].map(|a| first[a] + node[a]));
                        let got = values[i + BRICK_EDGE * (j + BRICK_EDGE * k)];
                        assert_eq!(got.to_bits(), want.to_bits(), "{b:?} {node:?}");
                    }
                }
            }
        }
    }

    /// On the volume's own grid, bricks whose supporting coefficients all lie on one side are
    /// sorted without being evaluated, and every node of theirs does lie on that side.
    #[test]
    fn bricks_of_one_sided_coefficients_are_sorted_unevaluated_and_right() {
        let v = two_balls(Basis::Bspline3);
        let whole = pgvol_field::fit::node_values_sparse(&v);
        let counts = v.grid.dims.map(|n| n.div_ceil(BRICK_EDGE));
        for iso in [0.0, 0.1, -0.05] {
            let sampler = Sampler::new(&v, &v.grid, iso, 0..counts[2]);
            let mut decided = 0;
            for k in 0..counts[2] {
                for j in 0..counts[1] {
                    for i in 0..counts[0] {
                        let b = [i, j, k];
                        if sampler.bound(b).is_some() {
                            continue;
                        }
                        let Some(above) = sampler.support_side(b) else {
                            continue;
                        };
                        decided += 1;
                        let (lo, n) = brick_extent(&v.grid, b);
                        for z in 0..n[2] {
                            for y in 0..n[1] {
                                for x in 0..n[0] {
                                    let value = whole.get([lo[0] + x, lo[1] + y, lo[2] + z]);
                                    assert_eq!(value < iso, !above, "brick {b:?} iso {iso}");
                                }
                            }
                        }
                    }
                }
            }
            assert!(
                decided > 0,
                "iso {iso}: no brick decided by its coefficients"
            );
        }
    }

    /// Every active block of full sampling is a candidate, and the boxes read hold the same
    /// sides as full sampling, with bounds standing in for some values.
    #[test]
    fn boxes_keep_the_sides_of_full_sampling_and_skip_some_values() {
        let bases = [
            Basis::Trilinear,
            Basis::Bspline2,
            Basis::Bspline3,
            Basis::Pg { n: 3, r: 1.5 },
        ];
        for basis in bases {
            let v = two_balls(basis);
            for iso in [0.0, 0.1, -0.05] {
                let full = v.sample(&v.grid);
                let full = PaddedNodes::new(&full, v.grid.dims, iso + v.grid.spacing);
                let sparse = VolumeNodes::new(&v, &v.grid, iso, None);
                let candidates = sparse.candidates(iso);
                let active = full.candidates(iso);
                assert!(active.iter().all(|id| candidates.binary_search(id).is_ok()));
                let counts = full.dims().map(|n| n.div_ceil(BLOCK));
                let (mut same, mut total) = (0, 0);
                for &id in &candidates {
                    let o = origin(counts, id);
                    let n = box_nodes(full.dims(), o);
                    let (mut a, mut b) = ([0.0; BOX_NODES], [0.0; BOX_NODES]);
                    full.read_box(o, n, &mut a);
                    sparse.read_box(o, n, &mut b);
                    for k in 0..n[2] {
                        for j in 0..n[1] {
                            for i in 0..n[0] {
                                let (f, s) = (a[box_index([i, j, k])], b[box_index([i, j, k])]);
                                assert_eq!(f < iso, s < iso, "{basis:?} iso {iso}: {f} vs {s}");
                                same += usize::from(f == s);
                                total += 1;
                            }
                        }
                    }
                }
                let skipped = same < total;
                assert_eq!(skipped, basis.is_separable(), "{basis:?} iso {iso}");
            }
        }
    }
}
