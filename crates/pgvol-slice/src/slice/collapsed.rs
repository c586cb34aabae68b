//! A separable coefficient volume restricted to one axis-aligned plane: the coefficients summed
//! along the axis with the plane's weights (4 per column for the cubic B-spline), kept brick by
//! brick. Columns whose bricks are all absent collapse to one value per brick, so building a
//! plane costs the band's bricks, and each plane brick knows the range of its values, which
//! bounds the field over every point whose support lies in it (the weights are a convex
//! combination).

use std::cell::OnceCell;

use glam::Vec3;
use pgvol_core::Background;
use pgvol_core::BRICK_EDGE;
use pgvol_field::kernel::{axis_window, AxisWindow, Profile};
use pgvol_field::{mirror, Grid};

use super::bricks::{beside, brick_counts, plane_axes, BrickLayer, INSIDE, OUTSIDE};
use super::cubic::{shift_cubic, CubicPieces};
use super::plane::{edge_root, LayerField};

const E: usize = BRICK_EDGE;
/// Coefficients per edge of the squares whose value ranges bound the field finely.
const CELL: usize = 2;
const CELLS: usize = E / CELL;

/// Where the values of a plane brick (or a part of one) lie.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Sign {
    /// All > 0.
    Outside,
    /// All < 0 (with a margin, so no sum of them rounds to zero).
    Inside,
    Mixed,
}

/// Below this a value is safely negative: a convex combination of such values stays below 0.
const INSIDE_MARGIN: f32 = -1e-20;

fn sign_of(lo: f32, hi: f32) -> Sign {
    if lo > 0.0 {
        Sign::Outside
    } else if hi < INSIDE_MARGIN {
        Sign::Inside
    } else {
        Sign::Mixed
    }
}

/// One plane brick.
enum Tile {
    /// Every column absent: one value.
    Uniform(f32),
    /// Some column stored: the values, computed when first read.
    Stored {
        sign: Sign,
        values: OnceCell<Box<StoredTile>>,
    },
}

struct StoredTile {
    values: [f32; E * E],
    /// Sign of each `CELL`² square of values, the first axis fastest.
    cells: [Sign; CELLS * CELLS],
    /// The squares' common sign, or `Mixed`.
    all: Sign,
}

/// Most collapsed tiles a thread keeps for its next planes (5 MiB).
const MAX_SPARE_TILES: usize = 16 * 1024;

thread_local! {
    /// Collapsed tiles of the planes this thread dropped, for its next planes to fill: a plane
    /// collapses a thousand tiles or so, and allocating and freeing each cost 3 % of a slicing.
    // Boxed: tiles pass between a plane's cells and this list as they are, not copied.
    #[allow(clippy::vec_box)]
    static SPARE_TILES: std::cell::RefCell<Vec<Box<StoredTile>>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

impl Drop for CollapsedPlane<'_, '_> {
    fn drop(&mut self) {
        SPARE_TILES.with(|spare| {
            let mut spare = spare.borrow_mut();
            for tile in self.tiles.drain(..) {
                if spare.len() >= MAX_SPARE_TILES {
                    break;
                }
                if let Tile::Stored { values, .. } = tile {
                    spare.extend(values.into_inner());
                }
            }
        });
    }
}

/// A plane brick's slot not set when the plane was made.
const UNRESOLVED: u32 = u32::MAX;

/// How far, in grid spacings, a cubic piece of the field along a segment is carried past its
/// knot interval rather than starting another piece. The B-spline's pieces meet with two
/// continuous derivatives, so carried that far a piece differs from its neighbour by about
/// 1e-10 of the coefficients' scale, far below f32 rounding of the field.
const KNOT_SNAP: f32 = 1e-3;

/// Per tap (node layer along the axis): its weight, brick layer and offset within a brick.
type Tap<'w, 's> = (f32, &'w BrickLayer<'s>, usize);

pub(crate) struct CollapsedPlane<'w, 's> {
    /// Coefficients per axis of the plane.
    dims: [usize; 2],
    /// Plane bricks per axis.
    counts: [usize; 2],
    /// Per plane brick, its tile, or [`UNRESOLVED`] for one absent in every tap whose tile
    /// [`Self::slot`] works out from the taps' sides.
    slots: Vec<u32>,
    tiles: Vec<Tile>,
    /// Plane bricks holding a crossing or beside one of the other side, as (u, v) brick indices.
    edges: Vec<[usize; 2]>,
    taps: Vec<Tap<'w, 's>>,
    /// Brick-relative offsets of the plane's two axes.
    stride: [usize; 2],
    background: Background,
    origin: [f32; 2],
    spacing: f32,
    profile: Profile,
    /// Distance of the plane from the grid box along the axis.
    off_axis: f32,
    /// The layer grid's node windows, where the slicing worked them out.
    node_windows: Option<&'w NodeWindows>,
}

/// The union of two ascending lists, ascending and without repeats.
fn merge_sorted(a: &[u32], b: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let next = match (a.get(i), b.get(j)) {
            (Some(&x), Some(&y)) if x <= y => {
                i += 1;
                j += usize::from(x == y);
                x
            }
            (_, Some(&y)) => {
                j += 1;
                y
            }
            (Some(&x), None) => {
                i += 1;
                x
            }
            (None, None) => unreachable!("one list has more"),
        };
        out.push(next);
    }
    out
}

/// A sampled block's coefficients, gathered, and summed across each node row: the field along
/// an edge between two of the block's nodes is a few of these sums (a row's, or a column's
/// summed on demand) in cubic pieces.
#[derive(Default)]
pub(crate) struct BlockLines {
    /// Whether the coefficients were gathered (when they are few next to the nodes' reads);
    /// the rest is meaningful only then.
    pub(super) gathered: bool,
    /// First coefficient index and count along u, then along v.
    u0: i64,
    nu: usize,
    v0: i64,
    /// The coefficients `[u0, u0 + nu) × [v0, …)`, u fastest.
    local: Vec<f32>,
    /// Per node row j, the coefficients summed along v with the row's weights: `nu` each.
    rows: Vec<f32>,
    /// The block's first node in the layer grid.
    first: [usize; 2],
    /// Per node column i: its window along u and distance beyond the box, where the plane
    /// has no [`NodeWindows`] (whose own are read in place).
    columns: Vec<NodeWindow>,
    /// Per node row j: its window along v and distance beyond the box, likewise.
    row_windows: Vec<NodeWindow>,
}

impl BlockLines {
    /// The window of node column `i` along u, with its distance beyond the box.
    #[inline]
    fn column<'a>(&'a self, plane: &'a CollapsedPlane, i: usize) -> &'a NodeWindow {
        match plane.node_windows {
            Some(NodeWindows([along_u, _])) => &along_u[self.first[0] + i],
            None => &self.columns[i],
        }
    }

    /// The window of node row `j` along v, with its distance beyond the box.
    #[inline]
    fn row<'a>(&'a self, plane: &'a CollapsedPlane, j: usize) -> &'a NodeWindow {
        match plane.node_windows {
            Some(NodeWindows([_, along_v])) => &along_v[self.first[1] + j],
            None => &self.row_windows[j],
        }
    }
}

/// [`axis_window`] at `u ≥ 0`, the cubic profile's weights computed here by the same
/// expressions: it is the innermost step of root finding, and inlined it costs a third.
#[inline]
fn window_at(profile: Profile, u: f32, n: usize) -> AxisWindow {
    if profile != Profile::Cubic {
        return axis_window(profile, u, n);
    }
    // ⌊u⌋ for u ≥ 0 without a call to floor.
    let c = (u as i64).clamp(0, n as i64 - 2);
    let t = u - (c - 1) as f32;
    let mut w = [[0.0f32; 3]; 4];
    for (a, slot) in w.iter_mut().enumerate() {
        let x = t - a as f32;
        let m = x.abs();
        slot[0] = if m < 1.0 {
            2.0 / 3.0 - x * x + 0.5 * m * m * m
        } else if m < 2.0 {
            let b = 2.0 - m;
            b * b * b / 6.0
        } else {
            0.0
        };
    }
    AxisWindow {
        first: c - 1,
        len: 4,
        w,
    }
}

/// The window at `x` along an axis of `n` nodes from `origin`, `x` clamped into the grid box,
/// with the distance beyond it.
#[inline]
fn clamped_window(
    origin: f32,
    spacing: f32,
    n: usize,
    profile: Profile,
    x: f32,
) -> (AxisWindow, f32) {
    let top = origin + spacing * (n - 1) as f32;
    let q = x.clamp(origin, top);
    (window_at(profile, (q - origin) / spacing, n), x - q)
}

/// A node coordinate's window along its axis, with its distance beyond the box.
type NodeWindow = (AxisWindow, f32);

/// The windows of a layer grid's node coordinates along the two plane axes: the same for every
/// layer of a slicing, so worked out once for them all.
pub(crate) struct NodeWindows([Vec<NodeWindow>; 2]);

impl NodeWindows {
    /// For planes across grid axis `axis`, at the node coordinates `nodes` along the plane's
    /// two axes.
    pub(crate) fn new(grid: &Grid, profile: Profile, axis: usize, nodes: [&[f32]; 2]) -> Self {
        let axes = plane_axes(axis);
        NodeWindows([0, 1].map(|k| {
            let a = axes[k];
            nodes[k]
                .iter()
                .map(|&x| clamped_window(grid.origin[a], grid.spacing, grid.dims[a], profile, x))
                .collect()
        }))
    }
}

/// The node layers (mirrored into the grid) and weights of the plane at height `h` along
/// `axis`, with the height clamped into the grid.
pub(crate) fn taps(grid: &Grid, profile: Profile, axis: usize, h: f32) -> (AxisWindow, f32) {
    let (lo, hi) = (grid.origin[axis], grid.max_corner()[axis]);
    let q = h.clamp(lo, hi);
    (
        axis_window(profile, (q - lo) / grid.spacing, grid.dims[axis]),
        q,
    )
}

/// The node layers the plane at height `h` reads.
pub(crate) fn tap_layers(grid: &Grid, profile: Profile, axis: usize, h: f32) -> Vec<usize> {
    let (w, _) = taps(grid, profile, axis, h);
    (0..w.len)
        .map(|t| mirror(w.first + t as i64, grid.dims[axis]))
        .collect()
}

impl<'w, 's> CollapsedPlane<'w, 's> {
    /// The plane at height `h` along grid axis `axis`; `layer(n)` gives brick layer `n`, which
    /// must hold every node layer of [`tap_layers`]. `node_windows`, where given, are those of
    /// the layer grid's nodes, sampled by node index.
    pub(crate) fn new(
        grid: &Grid,
        background: Background,
        profile: Profile,
        axis: usize,
        h: f32,
        layer: &dyn Fn(usize) -> &'w BrickLayer<'s>,
        node_windows: Option<&'w NodeWindows>,
    ) -> Self {
        let [b, c] = plane_axes(axis);
        let (window, q) = taps(grid, profile, axis, h);
        let counts3 = brick_counts(grid.dims);
        let counts = [counts3[b], counts3[c]];
        let stride3 = [1, E, E * E];
        let layers: Vec<usize> = (0..window.len)
            .map(|t| mirror(window.first + t as i64, grid.dims[axis]))
            .collect();
        let taps: Vec<Tap> = (0..window.len)
            .map(|t| {
                let n = layers[t];
                (window.w[t][0], layer(n / E), (n % E) * stride3[axis])
            })
            .collect();
        // Plane bricks whose columns are all absent share one tile per combination of sides:
        // tile `key` has tap t's brick inside where bit t of `key` is set. Each is summed as a
        // column of coefficients is, so the value is the same float.
        let mut tiles: Vec<Tile> = (0..1usize << taps.len())
            .map(|key| {
                let mut value = 0.0f32;
                for (t, (w, _, _)) in taps.iter().enumerate() {
                    value += w * background.value(key >> t & 1 == 1);
                }
                Tile::Uniform(value)
            })
            .collect();
        let mut slots = vec![UNRESOLVED; counts[0] * counts[1]];
        // The boundary positions of some tap's brick layer; taps in one brick layer share its
        // list. Every stored position is among them, and every position whose tile may differ
        // from a neighbour's: the others are read through [`Self::slot`].
        let first: &'w BrickLayer<'s> = taps[0].1;
        let mut merged: Option<Vec<u32>> = None;
        for (t, (_, l, _)) in taps.iter().enumerate().skip(1) {
            if !taps[..t].iter().any(|(_, m, _)| std::ptr::eq(*m, *l)) {
                let so_far = merged.as_deref().unwrap_or(first.boundary());
                merged = Some(merge_sorted(so_far, l.boundary()));
            }
        }
        let boundary = merged.as_deref().unwrap_or(first.boundary());
        // The boundary positions some tap's brick is not absent and outside at.
        let mut occupied = Vec::with_capacity(boundary.len());
        for &k in boundary {
            let k = k as usize;
            let states = taps.iter().map(|(_, l, _)| l.state(k));
            if states.clone().all(|s| s == OUTSIDE) {
                continue;
            }
            occupied.push(k as u32);
            if states.clone().all(|s| s >= INSIDE) {
                let key = states
                    .enumerate()
                    .fold(0, |key, (t, s)| key | usize::from(s == INSIDE) << t);
                slots[k] = key as u32;
                continue;
            }
            slots[k] = tiles.len() as u32;
            // A convex combination lies within its terms' range.
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for (t, (_, l, _)) in taps.iter().enumerate() {
                let s = l.state(k);
                let [a, z] = if s >= INSIDE {
                    let x = background.value(s == INSIDE);
                    [x, x]
                } else {
                    l.ranges[s as usize][layers[t] % E]
                };
                (lo, hi) = (lo.min(a), hi.max(z));
            }
            tiles.push(Tile::Stored {
                sign: sign_of(lo, hi),
                values: OnceCell::new(),
            });
        }
        let mut plane = CollapsedPlane {
            dims: [grid.dims[b], grid.dims[c]],
            counts,
            slots,
            tiles,
            edges: Vec::new(),
            taps,
            stride: [stride3[b], stride3[c]],
            background,
            origin: [grid.origin[b], grid.origin[c]],
            spacing: grid.spacing,
            profile,
            off_axis: h - q,
            node_windows,
        };
        plane.edges = plane.find_edges(&occupied);
        plane
    }

    /// The plane bricks whose values may change side within them or toward a neighbour; only
    /// `occupied` ones and their neighbours can: every other plane brick has the tile of all its
    /// neighbours, or that of slot 0 (absent and outside in every tap) and neighbours that are
    /// in `occupied` or have it too.
    fn find_edges(&self, occupied: &[u32]) -> Vec<[usize; 2]> {
        let cu = self.counts[0];
        let mut marked: Vec<usize> = Vec::new();
        for &k in occupied {
            let k = k as usize;
            let beside = beside(k, self.counts);
            // Amid plane bricks sharing its uniform tile (the inside of a part, mostly):
            // nothing changes side.
            let slot = self.slot(k);
            if matches!(self.tiles[slot], Tile::Uniform(_))
                && beside.iter().flatten().all(|&n| self.slot(n) == slot)
            {
                continue;
            }
            let s = self.sign(k);
            if s == Sign::Mixed {
                marked.push(k);
                continue;
            }
            for n in beside.into_iter().flatten() {
                if self.sign(n) != s {
                    marked.extend([k, n]);
                }
            }
        }
        marked.sort_unstable();
        marked.dedup();
        marked.into_iter().map(|k| [k % cu, k / cu]).collect()
    }

    /// The tile of plane brick `k`: the one set when the plane was made, or, for a brick absent
    /// in every tap, that of its sides.
    #[inline]
    fn slot(&self, k: usize) -> usize {
        match self.slots[k] {
            UNRESOLVED => self.taps.iter().enumerate().fold(0, |key, (t, (_, l, _))| {
                key | usize::from(l.state(k) == INSIDE) << t
            }),
            slot => slot as usize,
        }
    }

    /// The sign of plane brick `k`, exact where its bound is not.
    fn sign(&self, k: usize) -> Sign {
        match &self.tiles[self.slot(k)] {
            Tile::Uniform(v) => sign_of(*v, *v),
            Tile::Stored {
                sign: Sign::Mixed, ..
            } => self.stored(k).all,
            Tile::Stored { sign, .. } => *sign,
        }
    }

    /// The values of stored plane brick `k`.
    fn stored(&self, k: usize) -> &StoredTile {
        let Tile::Stored { values, .. } = &self.tiles[self.slot(k)] else {
            unreachable!("plane brick {k} is uniform")
        };
        values.get_or_init(|| self.collapse(k))
    }

    /// Sums the columns of plane brick `k` with the taps' weights.
    fn collapse(&self, k: usize) -> Box<StoredTile> {
        pgvol_core::cpu::run(Collapse(self, k))
    }

    /// [`Self::collapse`], inlined into both builds of its kernel.
    #[inline(always)]
    fn collapse_here(&self, k: usize) -> Box<StoredTile> {
        let (kb, kc) = (k % self.counts[0], k / self.counts[0]);
        let len = [E.min(self.dims[0] - kb * E), E.min(self.dims[1] - kc * E)];
        let mut out = SPARE_TILES
            .with(|spare| spare.borrow_mut().pop())
            .unwrap_or_else(|| {
                Box::new(StoredTile {
                    values: [0.0; E * E],
                    cells: [Sign::Mixed; CELLS * CELLS],
                    all: Sign::Mixed,
                })
            });
        out.values.fill(0.0);
        out.all = Sign::Mixed;
        // Tap by tap over the whole brick, each value summed in the taps' order.
        // The brick test is outside the loops and rows along a contiguous first axis are
        // sliced, so the inner loops vectorise; a whole tile whose rows follow each other in
        // the brick is one run.
        let whole = len == [E, E] && self.stride == [1, E];
        for &(w, l, off) in &self.taps {
            let s = l.state(k);
            if whole {
                if s >= INSIDE {
                    let x = w * self.background.value(s == INSIDE);
                    out.values.iter_mut().for_each(|o| *o += x);
                } else {
                    l.bricks[s as usize].add_run(off, w, &mut out.values);
                }
                continue;
            }
            for jc in 0..len[1] {
                let row = &mut out.values[E * jc..E * jc + len[0]];
                if s >= INSIDE {
                    let x = w * self.background.value(s == INSIDE);
                    row.iter_mut().for_each(|o| *o += x);
                    continue;
                }
                let values = &l.bricks[s as usize];
                let start = jc * self.stride[1] + off;
                if self.stride[0] == 1 {
                    values.add_run(start, w, row);
                } else {
                    values.add_strided(start, self.stride[0], w, row);
                }
            }
        }
        let mut ranges = [[f32::INFINITY, f32::NEG_INFINITY]; CELLS * CELLS];
        for jc in 0..len[1] {
            for jb in 0..len[0] {
                let value = out.values[jb + E * jc];
                let r = &mut ranges[jb / CELL + CELLS * (jc / CELL)];
                // Branch-free: which values are the least and greatest is not predictable.
                r[0] = r[0].min(value);
                r[1] = r[1].max(value);
            }
        }
        for (cell, r) in out.cells.iter_mut().zip(ranges) {
            // Squares past the grid's last coefficient hold none: any side will do.
            *cell = if r[0] > r[1] {
                Sign::Outside
            } else {
                sign_of(r[0], r[1])
            };
        }
        let first = out.cells[0];
        if out.cells.iter().all(|&c| c == first) {
            out.all = first;
        }
        out
    }

    #[inline]
    fn coefficient(&self, iu: usize, iv: usize) -> f32 {
        let k = iu / E + self.counts[0] * (iv / E);
        match &self.tiles[self.slot(k)] {
            Tile::Uniform(v) => *v,
            Tile::Stored { .. } => self.stored(k).values[iu % E + E * (iv % E)],
        }
    }

    /// The coefficients at `u0 + r` (r < `nu`) and `v0 + t` (t < `out.len() / nu`), mirrored
    /// into the grid, into `out[r + nu · t]`; the same values as [`Self::coefficient`], a
    /// tile's run along u copied at once.
    fn gather(&self, u0: i64, nu: usize, v0: i64, out: &mut [f32]) {
        let inside_u = u0 >= 0 && u0 + nu as i64 <= self.dims[0] as i64;
        for (t, row) in out.chunks_exact_mut(nu).enumerate() {
            let iv = mirror(v0 + t as i64, self.dims[1]);
            if !inside_u {
                for (r, c) in row.iter_mut().enumerate() {
                    *c = self.coefficient(mirror(u0 + r as i64, self.dims[0]), iv);
                }
                continue;
            }
            let mut done = 0;
            while done < nu {
                let iu = u0 as usize + done;
                let run = (E - iu % E).min(nu - done);
                let k = iu / E + self.counts[0] * (iv / E);
                let part = &mut row[done..done + run];
                match &self.tiles[self.slot(k)] {
                    Tile::Uniform(v) => part.fill(*v),
                    Tile::Stored { .. } => {
                        let first = iu % E + E * (iv % E);
                        part.copy_from_slice(&self.stored(k).values[first..first + run]);
                    }
                }
                done += run;
            }
        }
    }

    /// The sign of the coefficients `[u0, u1] × [v0, v1]`, at the finest resolution held.
    fn sign_over(&self, u: (usize, usize), v: (usize, usize)) -> Sign {
        let mut all = None;
        let mut meet = |s: Sign| {
            if s == Sign::Mixed || all.is_some_and(|a| a != s) {
                return false;
            }
            all = Some(s);
            true
        };
        for tv in v.0 / E..=v.1 / E {
            for tu in u.0 / E..=u.1 / E {
                let k = tu + self.counts[0] * tv;
                match &self.tiles[self.slot(k)] {
                    Tile::Stored {
                        sign: Sign::Mixed, ..
                    } => {
                        let t = self.stored(k);
                        let cu = (
                            u.0.max(tu * E) % E / CELL,
                            u.1.min(tu * E + E - 1) % E / CELL,
                        );
                        let cv = (
                            v.0.max(tv * E) % E / CELL,
                            v.1.min(tv * E + E - 1) % E / CELL,
                        );
                        for jv in cv.0..=cv.1 {
                            for ju in cu.0..=cu.1 {
                                if !meet(t.cells[ju + CELLS * jv]) {
                                    return Sign::Mixed;
                                }
                            }
                        }
                    }
                    _ => {
                        if !meet(self.sign(k)) {
                            return Sign::Mixed;
                        }
                    }
                }
            }
        }
        all.unwrap_or(Sign::Mixed)
    }

    /// The cubic B-spline field along plane axis `k` from `x[0]` to `x[1]` (at most one spacing,
    /// inside the box) as polynomials in the fraction of the way, one per knot interval crossed;
    /// `line(r)` is the coefficient at index `first + r` with the fixed axis summed out. `None`
    /// for other profiles and for segments that leave the box, which [`LayerField::value`] serves.
    fn cubic_pieces(
        &self,
        k: usize,
        x: [f32; 2],
        first: i64,
        len: usize,
        line: impl Fn(usize) -> f32,
    ) -> Option<CubicPieces> {
        let inside = |x: f32| x >= self.origin[k] && x <= self.top(k);
        if self.profile != Profile::Cubic || !inside(x[0]) || !inside(x[1]) {
            return None;
        }
        let g = x.map(|x| (x - self.origin[k]) / self.spacing);
        let n = self.dims[k] as i64;
        // The knot interval of a grid coordinate, as `window_at` picks it.
        let knot = |g: f32| (g as i64).clamp(0, n - 2);
        // Knot intervals reaching less than `KNOT_SNAP` into the segment are left to their
        // neighbours' pieces, so that a segment between nodes that sit on knots, which
        // rounding puts a hair to either side, is one piece rather than three.
        let (lo, hi) = (g[0].min(g[1]), g[0].max(g[1]));
        let mid = 0.5 * (lo + hi);
        let (c0, c1) = (
            knot((lo + KNOT_SNAP).min(mid)),
            knot((hi - KNOT_SNAP).max(mid)),
        );
        if c1 > c0 + 1 {
            return None;
        }
        let piece = |c: i64| -> Option<[f32; 4]> {
            let r = usize::try_from(c - 1 - first).ok()?;
            if r + 4 > len {
                return None;
            }
            let [a, b, cc, d] = [line(r), line(r + 1), line(r + 2), line(r + 3)];
            // The four uniform cubic B-splines over the interval, in powers of x = g − c,
            // then x = g0 − c + (g1 − g0)·t substituted.
            let p = [
                (a + 4.0 * b + cc) / 6.0,
                0.5 * (cc - a),
                0.5 * (a - 2.0 * b + cc),
                (3.0 * (b - cc) + d - a) / 6.0,
            ];
            Some(shift_cubic(p, g[0] - c as f32, g[1] - g[0]))
        };
        // With a knot inside the segment, the split is where g crosses it.
        let split = if c1 > c0 {
            let t = (c1 as f32 - g[0]) / (g[1] - g[0]);
            t.is_finite().then_some(t)?
        } else {
            f32::INFINITY
        };
        let (below, above) = if g[1] >= g[0] { (c0, c1) } else { (c1, c0) };
        Some(CubicPieces {
            split,
            first: piece(below)?,
            second: if c1 > c0 { piece(above)? } else { [0.0; 4] },
        })
    }

    fn top(&self, k: usize) -> f32 {
        self.origin[k] + self.spacing * (self.dims[k] - 1) as f32
    }

    /// The clamped grid coordinate along plane axis `k`, with the distance beyond the box.
    #[inline]
    fn window(&self, k: usize, x: f32) -> (AxisWindow, f32) {
        clamped_window(self.origin[k], self.spacing, self.dims[k], self.profile, x)
    }

    /// The coefficient indices along plane axis `k` that points in `[x0, x1]` read, mirrored
    /// ones included.
    fn support(&self, k: usize, x0: f32, x1: f32) -> (usize, usize) {
        let n = self.dims[k] as i64;
        // Every profile's window at grid coordinate g lies within [c − 1, c + 2] for
        // c = min(⌊g⌋, n − 2).
        let g = |x: f32| {
            let q = x.clamp(self.origin[k], self.top(k));
            // ⌊·⌋ of a coordinate ≥ 0 is its truncation, without a call to floor.
            (((q - self.origin[k]) / self.spacing) as i64).min(n - 2)
        };
        let (lo, hi) = (g(x0) - 1, g(x1) + 2);
        // Mirrored indices: below 0 they reach up to −lo, past n − 1 down to 2(n − 1) − hi.
        let first = lo.max(0).min(2 * (n - 1) - hi).max(0);
        let last = hi.min(n - 1).max(-lo).min(n - 1);
        (first as usize, last as usize)
    }
}

/// [`CollapsedPlane::collapse`] as a kernel: it reads the file's words of every plane brick a
/// layer's contours cross.
struct Collapse<'p, 'w, 's>(&'p CollapsedPlane<'w, 's>, usize);

impl pgvol_core::cpu::Kernel for Collapse<'_, '_, '_> {
    type Output = Box<StoredTile>;
    #[inline(always)]
    fn run(self) -> Box<StoredTile> {
        self.0.collapse_here(self.1)
    }
}

/// [`LayerField::sample`] of a collapsed plane as a kernel: the node values of every block a
/// contour may cross.
struct Sample<'p, 'w, 's, 'a> {
    plane: &'p CollapsedPlane<'w, 's>,
    first: [usize; 2],
    us: &'a [f32],
    vs: &'a [f32],
    out: &'a mut [f32],
    block: &'a mut BlockLines,
}

impl pgvol_core::cpu::Kernel for Sample<'_, '_, '_, '_> {
    type Output = ();
    #[inline(always)]
    fn run(self) {
        let Sample {
            plane,
            first,
            us,
            vs,
            out,
            block,
        } = self;
        let BlockLines {
            columns,
            row_windows,
            local,
            rows,
            ..
        } = block;
        // The nodes' windows, read in place where the slicing worked them out.
        let (wus, wvs): (&[NodeWindow], &[NodeWindow]) = match plane.node_windows {
            Some(NodeWindows([along_u, along_v])) => (
                &along_u[first[0]..first[0] + us.len()],
                &along_v[first[1]..first[1] + vs.len()],
            ),
            None => {
                columns.clear();
                row_windows.clear();
                columns.extend(us.iter().map(|&u| plane.window(0, u)));
                row_windows.extend(vs.iter().map(|&v| plane.window(1, v)));
                (columns, row_windows)
            }
        };
        let span = |ws: &[(AxisWindow, f32)]| {
            let lo = ws.iter().map(|w| w.0.first).min().unwrap_or(0);
            let hi = ws
                .iter()
                .map(|w| w.0.first + w.0.len as i64)
                .max()
                .unwrap_or(0);
            (lo, (hi - lo).max(0) as usize)
        };
        let ((u0, nu), (v0, nv)) = (span(wus), span(wvs));
        let gather = nu * nv <= 4 * us.len() * vs.len();
        local.clear();
        rows.clear();
        if gather {
            local.resize(nu * nv, 0.0);
            plane.gather(u0, nu, v0, local);
            rows.resize(nu * vs.len(), 0.0);
        }
        for (j, (wv, dv)) in wvs.iter().enumerate() {
            let line = if gather {
                &mut rows[nu * j..nu * (j + 1)]
            } else {
                &mut [][..]
            };
            if gather {
                // The row's coefficients summed along v, for every u the nodes read.
                for t in 0..wv.len {
                    let row = (wv.first + t as i64 - v0) as usize * nu;
                    let w = wv.w[t][0];
                    for (l, c) in line.iter_mut().zip(&local[row..row + nu]) {
                        *l += w * c;
                    }
                }
            }
            for (i, (wu, du)) in wus.iter().enumerate() {
                let mut value = 0.0f32;
                for r in 0..wu.len {
                    let line_r = if gather {
                        line[(wu.first + r as i64 - u0) as usize]
                    } else {
                        let iu = mirror(wu.first + r as i64, plane.dims[0]);
                        let mut sum = 0.0f32;
                        for t in 0..wv.len {
                            let iv = mirror(wv.first + t as i64, plane.dims[1]);
                            sum += wv.w[t][0] * plane.coefficient(iu, iv);
                        }
                        sum
                    };
                    value += wu.w[r][0] * line_r;
                }
                let outside = Vec3::new(*du, *dv, plane.off_axis).length();
                out[i + us.len() * j] = value + outside;
            }
        }
        (block.gathered, block.u0, block.nu, block.v0) = (gather, u0, nu, v0);
        block.first = first;
    }
}

impl LayerField for CollapsedPlane<'_, '_> {
    type Block = BlockLines;

    fn value(&self, u: f32, v: f32) -> f32 {
        let (wu, du) = self.window(0, u);
        let (wv, dv) = self.window(1, v);
        let mut value = 0.0f32;
        for t in 0..wv.len {
            let iv = mirror(wv.first + t as i64, self.dims[1]);
            let mut s = 0.0f32;
            for r in 0..wu.len {
                s += wu.w[r][0] * self.coefficient(mirror(wu.first + r as i64, self.dims[0]), iv);
            }
            value += wv.w[t][0] * s;
        }
        value + Vec3::new(du, dv, self.off_axis).length()
    }

    /// Each node sums its column taps first, then its row taps, as a plane collapsed row by row
    /// would. The coefficients the nodes read are gathered once when they are few next to the
    /// nodes' 16 reads each.
    fn sample(
        &self,
        first: [usize; 2],
        us: &[f32],
        vs: &[f32],
        out: &mut [f32],
        block: &mut BlockLines,
    ) {
        pgvol_core::cpu::run(Sample {
            plane: self,
            first,
            us,
            vs,
            out,
            block,
        })
    }

    /// From the block's row sums (along u) or its coefficients summed across the node's column
    /// on demand (along v), in the order [`LayerField::along`] sums them, so the zero is the
    /// same float.
    fn edge_zero(
        &self,
        b: &BlockLines,
        node: [usize; 2],
        p: [f32; 2],
        step: [f32; 2],
        ends: [f32; 2],
    ) -> f32 {
        let k = usize::from(step[0] == 0.0);
        let x = [p[k], p[k] + step[k]];
        if b.gathered {
            let pieces = if k == 0 {
                let row = &b.rows[b.nu * node[1]..b.nu * (node[1] + 1)];
                self.cubic_pieces(0, x, b.u0, b.nu, |r| row[r])
                    .map(|c| (c, b.row(self, node[1]).1))
            } else {
                let (w, beyond) = b.column(self, node[0]);
                let off = (w.first - b.u0) as usize;
                let nv = b.local.len() / b.nu;
                self.cubic_pieces(1, x, b.v0, nv, |r| {
                    let row = &b.local[b.nu * r + off..];
                    let mut sum = 0.0f32;
                    for (ws, c) in w.w.iter().zip(row).take(w.len) {
                        sum += ws[0] * c;
                    }
                    sum
                })
                .map(|c| (c, *beyond))
            };
            if let Some((pieces, beyond)) = pieces {
                let outside = Vec3::new(0.0, beyond, self.off_axis).length();
                return edge_root(&|t| pieces.at(t) + outside, ends[0], ends[1]);
            }
        }
        edge_root(&*self.along(p, step), ends[0], ends[1])
    }

    /// The coefficients the segment reads are gathered once; each point then sums them in
    /// [`LayerField::value`]'s order.
    fn along<'a>(&'a self, p: [f32; 2], step: [f32; 2]) -> Box<dyn Fn(f32) -> f32 + 'a> {
        // k: the axis the segment runs along; the other one is fixed.
        let k = usize::from(step[0] == 0.0);
        let at = move |t: f32| [p[0] + step[0] * t, p[1] + step[1] * t];
        let (w0, _) = self.window(k, at(0.0)[k]);
        let (w1, _) = self.window(k, at(1.0)[k]);
        let first = w0.first.min(w1.first);
        let len = ((w0.first.max(w1.first) + w0.len.max(w1.len) as i64) - first) as usize;
        if len > 8 {
            return Box::new(move |t| {
                let q = at(t);
                self.value(q[0], q[1])
            });
        }
        let (fixed, d_fixed) = self.window(1 - k, p[1 - k]);
        // patch[r][s]: r along the segment's axis, s over the fixed axis' taps.
        let mut patch = [[0.0f32; 4]; 8];
        let mut block = [0.0f32; 32];
        let block = &mut block[..len * fixed.len];
        if k == 0 {
            self.gather(first, len, fixed.first, block);
        } else {
            self.gather(fixed.first, fixed.len, first, block);
        }
        for (r, row) in patch.iter_mut().enumerate().take(len) {
            for (s, c) in row.iter_mut().enumerate().take(fixed.len) {
                *c = if k == 0 {
                    block[r + len * s]
                } else {
                    block[s + fixed.len * r]
                };
            }
        }
        if let Some(pieces) = self.cubic_pieces(k, [at(0.0)[k], at(1.0)[k]], first, len, |r| {
            let mut sum = 0.0f32;
            for (ws, c) in fixed.w.iter().zip(&patch[r]).take(fixed.len) {
                sum += ws[0] * c;
            }
            sum
        }) {
            let outside = Vec3::new(0.0, d_fixed, self.off_axis).length();
            return Box::new(move |t| pieces.at(t) + outside);
        }
        Box::new(move |t| {
            let q = at(t);
            let (w, d) = self.window(k, q[k]);
            let off = (w.first - first) as usize;
            let mut value = 0.0f32;
            if k == 0 {
                // Rows are the fixed v taps, each summed along u first.
                for (s, ws) in fixed.w.iter().enumerate().take(fixed.len) {
                    let mut sum = 0.0f32;
                    for (wr, row) in w.w.iter().zip(&patch[off..]).take(w.len) {
                        sum += wr[0] * row[s];
                    }
                    value += ws[0] * sum;
                }
                value + Vec3::new(d, d_fixed, self.off_axis).length()
            } else {
                for (wr, row) in w.w.iter().zip(&patch[off..]).take(w.len) {
                    let mut sum = 0.0f32;
                    for (ws, c) in fixed.w.iter().zip(row).take(fixed.len) {
                        sum += ws[0] * c;
                    }
                    value += wr[0] * sum;
                }
                value + Vec3::new(d_fixed, d, self.off_axis).length()
            }
        })
    }

    fn side_of(&self, u: [f32; 2], v: [f32; 2]) -> Option<bool> {
        let su = self.support(0, u[0], u[1]);
        let sv = self.support(1, v[0], v[1]);
        match self.sign_over(su, sv) {
            Sign::Outside => Some(false),
            // Beyond the grid box the distance to it is added, which may turn a value positive.
            Sign::Inside => {
                let within = |k: usize, x: [f32; 2]| x[0] >= self.origin[k] && x[1] <= self.top(k);
                (self.off_axis == 0.0 && within(0, u) && within(1, v)).then_some(true)
            }
            Sign::Mixed => None,
        }
    }

    fn uncertain(&self) -> Option<Vec<[[f32; 2]; 2]>> {
        if self.off_axis != 0.0 {
            return None;
        }
        // A point reads coefficients up to three below and two above its cell.
        let h = self.spacing;
        let span = |k: usize, t: usize| {
            let first = self.origin[k] + h * (t * E) as f32 - 3.0 * h;
            let last = self.origin[k] + h * (t * E + E) as f32 + 3.0 * h;
            [first, last]
        };
        let mut rects: Vec<[[f32; 2]; 2]> = self
            .edges
            .iter()
            .map(|&[tu, tv]| [span(0, tu), span(1, tv)])
            .collect();
        // Mirrored coefficients are read across the box's faces: near them, anything goes.
        for k in 0..2 {
            if self
                .edges
                .iter()
                .any(|t| t[k] == 0 || t[k] + 1 == self.counts[k])
            {
                return None;
            }
        }
        rects.shrink_to_fit();
        Some(rects)
    }

    fn known_box(&self) -> [[f32; 2]; 2] {
        [[self.origin[0], self.top(0)], [self.origin[1], self.top(1)]]
    }
}
