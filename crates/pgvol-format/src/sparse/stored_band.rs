//! Which coefficients the surface band needs: those within the basis reach (per axis) of a node
//! where the field is within `band` spacings of zero. The encoder stores every file brick
//! holding one, and may code the others in a stored brick more loosely (`free_words`).
//!
//! Judged on the field's node values, not the coefficients: a B-spline coefficient is not the
//! field value and can differ in sign from it near thin features. The search works file brick
//! by file brick on small windows of the grid, so it costs in proportion to the bricks near
//! stored coefficients, not to the grid: first the nodes near zero of every file brick whose
//! neighbourhood is not one background value far from zero, then the needed nodes of the file
//! bricks within reach of those.

use std::ops::Range;

use pgvol_core::{SparseGrid, BRICK_EDGE, BRICK_NODES};
use pgvol_field::{mirror, Basis, CoefficientVolume};
use rayon::prelude::*;

use super::bricks::Bricks;
use super::coverage::{Coverage, INSIDE, OUTSIDE, STORED};

/// A file brick to store, with the nodes the band needs.
pub(crate) struct KeptBrick {
    pub(crate) index: usize,
    pub(crate) needed: NodeRows,
}

/// Per row along x of a file brick's nodes (y fastest, then z): a bit per node, node `i` in
/// bit `i`. File bricks are at most 32 nodes wide (`BRICK_RANGE`). A bit rather than a byte
/// per node: the capped bunny's stored bricks at 2048³ held 280 MB of flags, at the peak of
/// its encoding.
pub(crate) type NodeRows = Box<[u32]>;

/// Rows of `width` nodes as a flag per node, x fastest.
pub(crate) fn node_flags(rows: &[u32], width: usize) -> impl Iterator<Item = bool> + '_ {
    rows.iter()
        .flat_map(move |&row| (0..width).map(move |i| row >> i & 1 == 1))
}

/// Rows of `width` nodes with every bit set.
pub(crate) fn every_node(width: usize, rows: usize) -> NodeRows {
    vec![low_bits(width) as u32; rows].into_boxed_slice()
}

/// Nodes a coefficient reaches, in grid spacings (per axis; Euclidean for pg, bounded by the
/// same number per axis).
pub(crate) fn dilation(basis: Basis) -> usize {
    match basis {
        Basis::Trilinear => 1,
        Basis::Bspline2 | Basis::Bspline3 => 2,
        Basis::Pg { r, .. } => r.ceil().max(1.0) as usize,
    }
}

/// Nodes per axis between a node and the farthest coefficient its field value reads.
fn value_reach(basis: Basis) -> usize {
    match basis {
        Basis::Trilinear => 0,
        Basis::Bspline2 | Basis::Bspline3 => 1,
        // A point a rounding error off its node reaches offsets up to ⌈r⌉.
        Basis::Pg { r, .. } => r.ceil() as usize,
    }
}

/// The file bricks holding a node the band needs, in brick order.
pub(crate) fn stored_band(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    coverage: &Coverage,
    band: f32,
) -> Vec<KeptBrick> {
    stored_band_layers(volume, bricks, coverage, band, 0..bricks.count[2])
}

/// What deciding the stored bricks of a range of file brick layers (along z) reads.
pub(crate) struct LayerReach {
    /// The file brick layers whose nodes near zero can make a brick of the range needed.
    pub(crate) near: Range<usize>,
    /// The file brick layers whose [`Coverage`] the decision reads.
    pub(crate) coverage: Range<usize>,
    /// The node layers whose coefficients it reads.
    pub(crate) nodes: Range<usize>,
}

/// [`LayerReach`] of the file brick layers `layers` for `basis`.
pub(crate) fn layer_reach(bricks: &Bricks, basis: Basis, layers: Range<usize>) -> LayerReach {
    let (e, nz) = (bricks.edge, bricks.dims[2]);
    let (d, reach) = (dilation(basis), value_reach(basis));
    // Layers of file bricks overlapping the nodes from `lo` to `hi`.
    let overlapping = |lo: usize, hi: usize| lo / e..hi.min(nz).div_ceil(e);
    let near = overlapping((layers.start * e).saturating_sub(d), layers.end * e + d);
    // A candidate's far-background test reads the coverage of the bricks within `reach` nodes.
    let coverage = overlapping((near.start * e).saturating_sub(reach), near.end * e + reach);
    // Coverage reads the grid's tables over its bricks; node values read `reach` nodes around
    // them, and one more for the rounding of a pg node's position.
    let nodes =
        (coverage.start * e).saturating_sub(reach + 1)..(coverage.end * e + reach + 1).min(nz);
    LayerReach {
        near,
        coverage,
        nodes,
    }
}

/// [`stored_band`] for the file brick layers `layers` along z: reads only what
/// [`layer_reach`] names, so a writer holding a window of the volume gets the same bricks.
pub(crate) fn stored_band_layers(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    coverage: &Coverage,
    band: f32,
    layers: Range<usize>,
) -> Vec<KeptBrick> {
    let limit = band * volume.grid.spacing;
    let far = FarBackground::new(volume, limit);
    let reach = value_reach(volume.basis);
    let per_layer = bricks.count[0] * bricks.count[1];
    let near = layer_reach(bricks, volume.basis, layers.clone()).near;
    let [xs, ys, zs] = uncovered_ranges(&far, coverage, bricks, reach, near);
    let rows: Vec<usize> = zs
        .flat_map(|k| ys.clone().map(move |j| bricks.count[0] * j + per_layer * k))
        .collect();
    let candidates: Vec<usize> = rows
        .into_par_iter()
        .flat_map_iter(|row| xs.clone().map(move |i| row + i))
        .filter(|&b| !far.covers(coverage, bricks, b, reach))
        .collect();
    let near_zero: Vec<(usize, NodeRows)> = candidates
        .par_iter()
        .map_init(Vec::new, |scratch, &b| {
            near_zero_nodes(volume, bricks, b, limit, scratch).map(|m| (b, m))
        })
        .flatten()
        .collect();
    let d = dilation(volume.basis);
    let wanted = layers.start * per_layer..layers.end * per_layer;
    let mut reached: Vec<usize> = Vec::new();
    for &(b, _) in &near_zero {
        let (lo, n) = bricks.extent(b);
        for_each_brick_in(bricks, grow(bricks, lo, n, d), |f| {
            if wanted.contains(&f) {
                reached.push(f)
            }
        });
    }
    reached.sort_unstable();
    reached.dedup();
    reached
        .par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |scratch, &b| {
                needed_nodes(bricks, &near_zero, b, d, scratch)
                    .map(|needed| KeptBrick { index: b, needed })
            },
        )
        .flatten()
        .collect()
}

/// File bricks a far outside background covers: those more than `reach` nodes from the
/// coverage's occupied box. Per axis, the range of the others (every brick when the outside
/// is not far, or along z within `near`).
fn uncovered_ranges(
    far: &FarBackground,
    coverage: &Coverage,
    bricks: &Bricks,
    reach: usize,
    near: Range<usize>,
) -> [Range<usize>; 3] {
    let whole = [0..bricks.count[0], 0..bricks.count[1], near.clone()];
    if !far.far[0] {
        return whole;
    }
    // A brick reads the coverage of bricks within `reach` nodes: this many bricks away.
    let g = reach / bricks.edge + 1;
    let occupied = coverage.occupied();
    std::array::from_fn(|a| {
        let r = &occupied[a];
        let lo = r.start.saturating_sub(g).max(whole[a].start);
        let hi = (r.end + g).min(whole[a].end);
        if r.is_empty() || lo >= hi {
            0..0
        } else {
            lo..hi
        }
    })
}

/// Whether a window of coefficients all equal to one background value `c` is sure to have no
/// node value near zero. Separable bases sum to one, so such a window's node values are `c` up
/// to rounding; pg weights are positive and a node's own is 1 up to where rounding puts the
/// node, so the value is at least `|c|` times that much.
struct FarBackground {
    /// `[outside, inside]`: whether a window of only that value is far from zero.
    far: [bool; 2],
    /// Whether the two sides have the same value.
    same: bool,
}

impl FarBackground {
    fn new(volume: &CoefficientVolume, limit: f32) -> FarBackground {
        let bg = volume.coeffs.background();
        let floor = own_weight_floor(volume);
        // Margin for the rounding of the sums (a few ulps).
        let far = |c: f32| c.abs() as f64 * floor * (1.0 - 1e-5) > limit as f64;
        FarBackground {
            far: [far(bg.outside), far(bg.inside)],
            same: bg.outside == bg.inside,
        }
    }

    /// Whether every coefficient within `reach` nodes of file brick `b` is one background value
    /// far from zero, so that none of its node values is near zero.
    fn covers(&self, coverage: &Coverage, bricks: &Bricks, b: usize, reach: usize) -> bool {
        let (lo, n) = bricks.extent(b);
        let mut flags = 0;
        for_each_brick_in(bricks, grow(bricks, lo, n, reach), |f| {
            flags |= coverage.flags(f)
        });
        if flags & STORED != 0 {
            return false;
        }
        match (flags & OUTSIDE != 0, flags & INSIDE != 0) {
            (true, false) => self.far[0],
            (false, true) => self.far[1],
            (true, true) => self.same && self.far[0],
            (false, false) => false,
        }
    }
}

/// A lower bound of the weight a pg node gives itself where `value` evaluates it: the node's
/// grid coordinates come back off by rounding, at most a few ulps of the largest coordinate
/// magnitude in grid units. 1 for separable bases, whose weights sum to one.
fn own_weight_floor(volume: &CoefficientVolume) -> f64 {
    let Basis::Pg { n, r } = volume.basis else {
        return 1.0;
    };
    let g = &volume.grid;
    let span = (0..3)
        .map(|a| {
            let far = g.origin[a].abs() as f64 + g.spacing as f64 * g.dims[a] as f64;
            far / g.spacing as f64 + g.dims[a] as f64
        })
        .fold(0.0, f64::max);
    let off = 16.0 * f32::EPSILON as f64 * span * 3f64.sqrt();
    let q = (off * off) / (r as f64 * r as f64);
    if q >= 1.0 {
        0.0
    } else {
        (1.0 - q).powi(n as i32 + 1)
    }
}

/// First node and node counts of the box `lo`, `n` grown by `d` nodes each way, clipped to the
/// grid.
fn grow(bricks: &Bricks, lo: [usize; 3], n: [usize; 3], d: usize) -> ([usize; 3], [usize; 3]) {
    let glo = lo.map(|c| c.saturating_sub(d));
    let ghi = [0, 1, 2].map(|a| (lo[a] + n[a] + d).min(bricks.dims[a]));
    (glo, [0, 1, 2].map(|a| ghi[a] - glo[a]))
}

/// Calls `f` with the index of every file brick the box `(lo, n)` overlaps, in brick order.
fn for_each_brick_in(bricks: &Bricks, (lo, n): ([usize; 3], [usize; 3]), mut f: impl FnMut(usize)) {
    let first = lo.map(|c| c / bricks.edge);
    let last = [0, 1, 2].map(|a| (lo[a] + n[a] - 1) / bricks.edge);
    let [cx, cy, _] = bricks.count;
    for k in first[2]..=last[2] {
        for j in first[1]..=last[1] {
            for i in first[0]..=last[0] {
                f(i + cx * (j + cy * k));
            }
        }
    }
}

/// Per node of file brick `b` (as [`NodeRows`]): whether the field there is within `limit` of
/// zero; `None` when no node is.
fn near_zero_nodes(
    volume: &CoefficientVolume,
    bricks: &Bricks,
    b: usize,
    limit: f32,
    scratch: &mut Vec<f32>,
) -> Option<NodeRows> {
    let (lo, n) = bricks.extent(b);
    let len = n[0] * n[1] * n[2];
    if matches!(volume.basis, Basis::Bspline2 | Basis::Bspline3) {
        // A node's value is a convex combination of the coefficients within one node of it,
        // so coefficients all beyond the limit on one side bound every value there. The
        // margins cover the rounding of the three passes (a few ulps, and no underflow to 0).
        let sure = limit * (1.0 + 1e-4) + 1e-30;
        let [least, most] = coefficient_range(&volume.coeffs, lo, n);
        if least > sure || most < -sure {
            return None;
        }
    }
    // The B-spline kernels as `pgvol_field::fit::node_values` applies them: the same bits.
    let values = match volume.basis {
        // File bricks made of whole grid bricks: each grid brick's node values by the field
        // crate's path (the same operations, with each neighbour brick looked up once).
        Basis::Bspline2 | Basis::Bspline3 if bricks.edge.is_multiple_of(BRICK_EDGE) => {
            grid_brick_values(volume, lo, n)
        }
        Basis::Bspline2 => blurred(&volume.coeffs, lo, n, (1.0 / 8.0, 6.0 / 8.0), scratch),
        Basis::Bspline3 => blurred(&volume.coeffs, lo, n, (1.0 / 6.0, 4.0 / 6.0), scratch),
        Basis::Pg { .. } => {
            let g = &volume.grid;
            let mut v = Vec::with_capacity(len);
            for k in lo[2]..lo[2] + n[2] {
                for j in lo[1]..lo[1] + n[1] {
                    for i in lo[0]..lo[0] + n[0] {
                        v.push(volume.value(g.point(i, j, k)));
                    }
                }
            }
            v
        }
        // The coefficients are the node values.
        Basis::Trilinear => {
            let mut v = vec![0.0; len];
            volume.coeffs.gather(lo, n, &mut v);
            v
        }
    };
    // Most bricks have no node near zero: decide that in one vectorised pass first.
    let closest = least_magnitude(&values);
    (closest <= limit).then(|| {
        values
            .chunks_exact(n[0])
            .map(|row| {
                let near = row.iter().enumerate();
                near.fold(0u32, |bits, (i, v)| bits | u32::from(v.abs() <= limit) << i)
            })
            .collect()
    })
}

/// The least and greatest coefficient within one node of the box of `n` nodes from `lo`
/// (clipped to the grid: a mirrored read falls inside the box), read brick by brick without a
/// copy. Two thirds of the bricks near the band hold no node near zero, and this tells most of
/// them for a fraction of their node values' cost.
fn coefficient_range(coeffs: &SparseGrid, lo: [usize; 3], n: [usize; 3]) -> [f32; 2] {
    let dims = coeffs.dims();
    let wlo = lo.map(|c| c.saturating_sub(1));
    let whi = [0, 1, 2].map(|a| (lo[a] + n[a] + 1).min(dims[a]));
    let (mut least, mut most) = (f32::INFINITY, f32::NEG_INFINITY);
    let first = wlo.map(|c| c / BRICK_EDGE);
    let last = whi.map(|c| (c - 1) / BRICK_EDGE);
    for gk in first[2]..=last[2] {
        for gj in first[1]..=last[1] {
            for gi in first[0]..=last[0] {
                let g = [gi, gj, gk];
                let Some(values) = coeffs.brick(g) else {
                    let v = coeffs.background_of(g);
                    (least, most) = (least.min(v), most.max(v));
                    continue;
                };
                // The window's part of brick `g`, in the brick's own node indices.
                let from = [0, 1, 2].map(|a| wlo[a].max(g[a] * BRICK_EDGE) - g[a] * BRICK_EDGE);
                let to = [0, 1, 2].map(|a| whi[a].min((g[a] + 1) * BRICK_EDGE) - g[a] * BRICK_EDGE);
                let mut lanes = Lanes::new(least, most);
                for k in from[2]..to[2] {
                    for j in from[1]..to[1] {
                        let row = BRICK_EDGE * (j + BRICK_EDGE * k);
                        lanes.add(&values[row + from[0]..row + to[0]]);
                    }
                }
                [least, most] = lanes.range();
            }
        }
    }
    [least, most]
}

/// The least `|v|` of the finite `values`, over [`LANES`] lanes as [`Lanes`] keeps them.
fn least_magnitude(values: &[f32]) -> f32 {
    let mut lanes = [f32::INFINITY; LANES];
    let mut chunks = values.chunks_exact(LANES);
    for chunk in &mut chunks {
        for (l, &v) in lanes.iter_mut().zip(chunk) {
            let a = v.abs();
            *l = if a < *l { a } else { *l };
        }
    }
    let rest = chunks.remainder().iter().map(|v| v.abs());
    lanes.into_iter().chain(rest).fold(f32::INFINITY, f32::min)
}

/// A running least and greatest value over [`LANES`] independent lanes, so that the compiler
/// keeps them in vector registers: a single running pair is a chain of dependent scalar
/// comparisons, which took a quarter of the stored band's search. The values are finite (a
/// volume's coefficients are checked first), where these comparisons agree with `f32::min`
/// and `f32::max` up to the sign of a zero, which no bound here depends on.
struct Lanes {
    least: [f32; LANES],
    most: [f32; LANES],
}

const LANES: usize = 8;

impl Lanes {
    fn new(least: f32, most: f32) -> Self {
        Lanes {
            least: [least; LANES],
            most: [most; LANES],
        }
    }

    #[inline]
    fn add(&mut self, values: &[f32]) {
        let mut chunks = values.chunks_exact(LANES);
        for chunk in &mut chunks {
            for ((l, m), &v) in self.least.iter_mut().zip(&mut self.most).zip(chunk) {
                *l = if v < *l { v } else { *l };
                *m = if v > *m { v } else { *m };
            }
        }
        for &v in chunks.remainder() {
            self.least[0] = if v < self.least[0] { v } else { self.least[0] };
            self.most[0] = if v > self.most[0] { v } else { self.most[0] };
        }
    }

    fn range(&self) -> [f32; 2] {
        let least = self.least.iter().fold(f32::INFINITY, |a, &v| a.min(v));
        let most = self.most.iter().fold(f32::NEG_INFINITY, |a, &v| a.max(v));
        [least, most]
    }
}

/// The field at the box of `n` nodes from `lo` (x fastest), a whole number of the sparse
/// grid's bricks from one of them, brick by brick through `brick_node_values_into`.
fn grid_brick_values(volume: &CoefficientVolume, lo: [usize; 3], n: [usize; 3]) -> Vec<f32> {
    let mut out = vec![0.0f32; n[0] * n[1] * n[2]];
    let mut brick = [0.0f32; BRICK_NODES];
    let first = lo.map(|c| c / BRICK_EDGE);
    let count = n.map(|c| c.div_ceil(BRICK_EDGE));
    for bz in 0..count[2] {
        for by in 0..count[1] {
            for bx in 0..count[0] {
                let b = [first[0] + bx, first[1] + by, first[2] + bz];
                pgvol_field::fit::brick_node_values_into(volume, b, &mut brick);
                let o = [bx, by, bz].map(|c| c * BRICK_EDGE);
                let m = [0, 1, 2].map(|a| (n[a] - o[a]).min(BRICK_EDGE));
                for k in 0..m[2] {
                    for j in 0..m[1] {
                        let src = BRICK_EDGE * (j + BRICK_EDGE * k);
                        let dst = o[0] + n[0] * (o[1] + j + n[1] * (o[2] + k));
                        out[dst..dst + m[0]].copy_from_slice(&brick[src..src + m[0]]);
                    }
                }
            }
        }
    }
    out
}

/// The B-spline field at the box of `n` nodes from `lo` (x fastest): the 3-tap kernel along x,
/// then y, then z over the coefficients around it, mirrored at the grid's ends, each node by
/// the same operations as `pgvol_field::fit::node_values`.
fn blurred(
    coeffs: &SparseGrid,
    lo: [usize; 3],
    n: [usize; 3],
    (side, centre): (f32, f32),
    scratch: &mut Vec<f32>,
) -> Vec<f32> {
    let dims = coeffs.dims();
    let clo = lo.map(|c| c.saturating_sub(1));
    let cn = [0, 1, 2].map(|a| (lo[a] + n[a] + 1).min(dims[a]) - clo[a]);
    scratch.resize(cn[0] * cn[1] * cn[2], 0.0);
    coeffs.gather(clo, cn, scratch);
    // Window positions of node `g`'s neighbours and itself along axis `a`.
    let taps_at = |a: usize, g: usize| {
        let at = |i: i64| mirror(i, dims[a]) - clo[a];
        (at(g as i64 - 1), at(g as i64 + 1), g - clo[a])
    };
    let tap = |p: f32, h: f32, q: f32| side * (p + q) + centre * h;
    // Along x: n[0] × cn[1] × cn[2].
    let mut x = Vec::with_capacity(n[0] * cn[1] * cn[2]);
    for row in scratch.chunks_exact(cn[0]) {
        for i in 0..n[0] {
            let (p, q, h) = taps_at(0, lo[0] + i);
            x.push(tap(row[p], row[h], row[q]));
        }
    }
    // Along y: n[0] × n[1] × cn[2].
    let mut y = Vec::with_capacity(n[0] * n[1] * cn[2]);
    for plane in x.chunks_exact(n[0] * cn[1]) {
        for j in 0..n[1] {
            let (p, q, h) = taps_at(1, lo[1] + j);
            for i in 0..n[0] {
                let at = |r: usize| plane[i + n[0] * r];
                y.push(tap(at(p), at(h), at(q)));
            }
        }
    }
    // Along z: n[0] × n[1] × n[2].
    let plane = n[0] * n[1];
    let mut z = Vec::with_capacity(plane * n[2]);
    for k in 0..n[2] {
        let (p, q, h) = taps_at(2, lo[2] + k);
        for s in 0..plane {
            z.push(tap(y[s + plane * p], y[s + plane * h], y[s + plane * q]));
        }
    }
    z
}

/// Per node of file brick `b` (as [`NodeRows`]): whether a node near zero (`near_zero`, sorted
/// by file brick) lies within `d` nodes per axis; `None` when none does. The window around the
/// brick is held as one bit mask per row along x, so the box dilation is shifts and ORs of
/// rows (a byte per node and a pass per node and axis took most of a 2048³ file's writing).
fn needed_nodes(
    bricks: &Bricks,
    near_zero: &[(usize, NodeRows)],
    b: usize,
    d: usize,
    (rows, spare): &mut (Vec<u64>, Vec<u64>),
) -> Option<NodeRows> {
    let (lo, n) = bricks.extent(b);
    let (wlo, wn) = grow(bricks, lo, n, d);
    debug_assert!(wn[0] <= 64, "a window row fits in 64 bits");
    let row_at = |j: usize, k: usize| j + wn[1] * k;
    rows.clear();
    rows.resize(wn[1] * wn[2], 0);
    for_each_brick_in(bricks, (wlo, wn), |f| {
        let Ok(at) = near_zero.binary_search_by_key(&f, |(b, _)| *b) else {
            return;
        };
        let near = &near_zero[at].1;
        let (flo, fnn) = bricks.extent(f);
        // The part of file brick `f` inside the window.
        let from = [0, 1, 2].map(|a| flo[a].max(wlo[a]));
        let to = [0, 1, 2].map(|a| (flo[a] + fnn[a]).min(wlo[a] + wn[a]));
        // Its rows' bits from `from[0]` to `to[0]`, moved to the window's x.
        let part = low_bits(to[0] - from[0]);
        let (skip, place) = (from[0] - flo[0], from[0] - wlo[0]);
        for k in from[2]..to[2] {
            for j in from[1]..to[1] {
                let src = j - flo[1] + fnn[1] * (k - flo[2]);
                rows[row_at(j - wlo[1], k - wlo[2])] |=
                    (u64::from(near[src]) >> skip & part) << place;
            }
        }
    });
    dilate_rows(rows, spare, wn, d);
    let off = [0, 1, 2].map(|a| lo[a] - wlo[a]);
    let brick_rows = (0..n[2])
        .flat_map(|k| (0..n[1]).map(move |j| (j, k)))
        .map(|(j, k)| rows[row_at(j + off[1], k + off[2])] >> off[0] & low_bits(n[0]));
    // Most bricks reached need no node: known from the row masks, before a flag per node.
    if brick_rows.clone().all(|row| row == 0) {
        return None;
    }
    // A brick is at most 32 nodes wide, so its rows fit.
    Some(brick_rows.map(|row| row as u32).collect())
}

/// The lowest `n` bits set.
fn low_bits(n: usize) -> u64 {
    if n >= 64 {
        u64::MAX
    } else {
        (1 << n) - 1
    }
}

/// `rows` (one bit mask per row along x of a box of `dims` nodes, rows y fastest then z) grown
/// by `d` nodes both ways along each axis, clipped to the box; `spare` is scratch.
fn dilate_rows(rows: &mut [u64], spare: &mut Vec<u64>, dims: [usize; 3], d: usize) {
    let width = low_bits(dims[0]);
    for row in rows.iter_mut() {
        let r = *row;
        *row = (1..=d).fold(r, |acc, s| acc | r << s | r >> s) & width;
    }
    // Along y within each plane, then along z across planes: each row ORs its neighbours
    // within `d` rows, read from a copy. Row indices come from the loops, not divisions (which
    // took most of the time here).
    let (ny, nz) = (dims[1], dims[2]);
    let within = |t: usize, n: usize| t.saturating_sub(d)..=(t + d).min(n - 1);
    spare.clear();
    spare.extend_from_slice(rows);
    for (plane, from) in rows.chunks_exact_mut(ny).zip(spare.chunks_exact(ny)) {
        for (j, row) in plane.iter_mut().enumerate() {
            *row = from[within(j, ny)].iter().fold(0, |acc, r| acc | r);
        }
    }
    spare.clear();
    spare.extend_from_slice(rows);
    for (k, plane) in rows.chunks_exact_mut(ny).enumerate() {
        let planes = within(k, nz);
        for (j, row) in plane.iter_mut().enumerate() {
            *row = planes.clone().fold(0, |acc, u| acc | spare[j + ny * u]);
        }
    }
}

/// `mask` (a box of `dims` nodes, x fastest) grown by `d` nodes both ways along one axis,
/// clipped to the box (a box dilation is three of these): the tests' reference.
#[cfg(test)]
fn dilate_along(mask: &mut [bool], dims: [usize; 3], axis: usize, d: usize) {
    let stride = [1, dims[0], dims[0] * dims[1]][axis];
    let n = dims[axis];
    let mut line = vec![false; n];
    // Node (inner, t, block) along the axis is at inner + stride · (t + n · block).
    for block in 0..mask.len() / (n * stride) {
        for inner in 0..stride {
            let start = inner + stride * n * block;
            for (t, l) in line.iter_mut().enumerate() {
                *l = mask[start + t * stride];
            }
            for t in 0..n {
                let (a, z) = (t.saturating_sub(d), (t + d).min(n - 1));
                mask[start + t * stride] = line[a..=z].contains(&true);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::test_volumes::{dense, sparse, BASES};
    use pgvol_core::Background;

    /// The lanes' range and least magnitude are those of one running pair, over slices of every
    /// length around the lane count, added in pieces.
    #[test]
    fn lanes_give_the_range_and_least_magnitude() {
        let mut s = 7u64;
        for len in 0..40 {
            let values: Vec<f32> = (0..len)
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    (s % 2001) as f32 / 100.0 - 10.0
                })
                .collect();
            let least = values.iter().copied().fold(f32::INFINITY, f32::min);
            let most = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            let mut lanes = Lanes::new(f32::INFINITY, f32::NEG_INFINITY);
            let (a, b) = values.split_at(len / 3);
            lanes.add(a);
            lanes.add(b);
            assert_eq!(lanes.range(), [least, most], "{len}");
            let magnitude = values.iter().fold(f32::INFINITY, |m, v| m.min(v.abs()));
            assert_eq!(least_magnitude(&values), magnitude, "{len}");
        }
    }

    #[test]
    fn dilation_grows_a_single_node_into_a_box_clipped_at_the_border() {
        let dims = [6, 5, 4];
        let mut mask = vec![false; 120];
        mask[1 + 6 * (2 + 5 * 3)] = true;
        for axis in 0..3 {
            dilate_along(&mut mask, dims, axis, 2);
        }
        for k in 0..4 {
            for j in 0..5 {
                for i in 0..6 {
                    let inside = i <= 3 && j <= 4 && k >= 1;
                    assert_eq!(mask[i + 6 * (j + 5 * k)], inside, "({i}, {j}, {k})");
                }
            }
        }
    }

    /// Rows of bits dilate as the flags per node do, for boxes thin and wide on each axis.
    #[test]
    fn row_dilation_is_the_box_dilation() {
        let mut s = 11u64;
        for dims in [[20, 20, 20], [1, 7, 3], [33, 1, 5], [5, 4, 1], [64, 9, 12]] {
            for d in [1, 2, 3] {
                let len = dims[0] * dims[1] * dims[2];
                let mask: Vec<bool> = (0..len)
                    .map(|_| {
                        s ^= s << 13;
                        s ^= s >> 7;
                        s ^= s << 17;
                        s.is_multiple_of(23)
                    })
                    .collect();
                let mut rows: Vec<u64> = mask
                    .chunks_exact(dims[0])
                    .map(|row| {
                        row.iter()
                            .enumerate()
                            .fold(0, |b, (i, &m)| b | u64::from(m) << i)
                    })
                    .collect();
                dilate_rows(&mut rows, &mut Vec::new(), dims, d);
                let mut want = mask;
                for axis in 0..3 {
                    dilate_along(&mut want, dims, axis, d);
                }
                let got: Vec<bool> = node_flags_wide(&rows, dims[0]).collect();
                assert_eq!(got, want, "{dims:?} d {d}");
            }
        }
    }

    /// [`node_flags`] for rows up to 64 nodes wide.
    fn node_flags_wide(rows: &[u64], width: usize) -> impl Iterator<Item = bool> + '_ {
        rows.iter()
            .flat_map(move |&row| (0..width).map(move |i| row >> i & 1 == 1))
    }

    /// The rule on the whole grid at once: every node's field value, dilated.
    fn needed_everywhere(volume: &CoefficientVolume, band: f32) -> Vec<bool> {
        let limit = band * volume.grid.spacing;
        let values = pgvol_field::fit::node_values(volume);
        let mut mask: Vec<bool> = values.iter().map(|v| v.abs() <= limit).collect();
        for axis in 0..3 {
            dilate_along(&mut mask, volume.grid.dims, axis, dilation(volume.basis));
        }
        mask
    }

    fn assert_same_band(volume: &CoefficientVolume, edge: usize, band: f32) {
        let bricks = Bricks::new(volume.grid.dims, edge);
        let coverage = Coverage::new(&volume.coeffs, &bricks);
        let kept = stored_band(volume, &bricks, &coverage, band);
        let want = needed_everywhere(volume, band);
        let [nx, ny, _] = volume.grid.dims;
        let mut next = kept.iter().peekable();
        for b in 0..bricks.total() {
            let (lo, n) = bricks.extent(b);
            let mut nodes = Vec::new();
            for k in lo[2]..lo[2] + n[2] {
                for j in lo[1]..lo[1] + n[1] {
                    nodes.extend((lo[0]..lo[0] + n[0]).map(|i| want[i + nx * (j + ny * k)]));
                }
            }
            let what = format!("{} brick {b} of edge {edge}, band {band}", volume.basis);
            if nodes.contains(&true) {
                let k = next.next().unwrap_or_else(|| panic!("{what} missing"));
                assert_eq!(k.index, b, "{what}");
                let needed: Vec<bool> = node_flags(&k.needed, n[0]).collect();
                assert_eq!(needed, nodes, "{what}");
            } else {
                assert!(next.peek().is_none_or(|k| k.index != b), "{what} kept");
            }
        }
        assert!(next.next().is_none());
    }

    #[test]
    fn brick_by_brick_finds_what_the_whole_grid_rule_finds() {
        for basis in BASES {
            let volumes = [
                dense([13, 7, 9], basis, 3, 0.5),
                dense([2, 11, 3], basis, 5, 2.0),
                sparse(basis, Background::clamp(0.3), 7),
                // Both sides negative, of different magnitudes.
                sparse(
                    basis,
                    Background {
                        outside: -0.25,
                        inside: -0.5,
                    },
                    9,
                ),
            ];
            for volume in &volumes {
                for edge in [2, 5, 8, 16] {
                    // The clamp 0.3 is within the band at 3 spacings, beyond it at 2.
                    for band in [0.0, 1.0, 2.0, 3.0] {
                        assert_same_band(volume, edge, band);
                    }
                }
            }
        }
    }

    #[test]
    fn uniform_background_is_skipped_but_a_change_of_side_is_not() {
        let volume = sparse(Basis::Bspline3, Background::clamp(0.3), 7);
        let bricks = Bricks::new(volume.grid.dims, 8);
        let coverage = Coverage::new(&volume.coeffs, &bricks);
        let far = FarBackground::new(&volume, 0.2);
        let index = |b: [usize; 3]| b[0] + 5 * (b[1] + 4 * b[2]);
        // Outside bricks all round.
        assert!(far.covers(&coverage, &bricks, index([2, 3, 0]), 1));
        // Next to a stored brick, and next to an inside one.
        assert!(!far.covers(&coverage, &bricks, index([1, 2, 1]), 1));
        assert!(!far.covers(&coverage, &bricks, index([1, 3, 0]), 1));
        // Within the band the background is near zero everywhere.
        let near = FarBackground::new(&volume, 0.3);
        assert!(!near.covers(&coverage, &bricks, index([2, 3, 0]), 1));
        // The lone inside corner brick, away from any stored one, has the surface at its corner.
        let kept = stored_band(&volume, &bricks, &coverage, 1.0);
        assert!(kept.iter().any(|k| k.index == index([0, 3, 0])));
    }
}
