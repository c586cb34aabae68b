//! The sparse node grid every stage shares: values in bricks of 8³ nodes, only the bricks near
//! the surface stored, every other brick a constant background (inside or outside).
//!
//! Bricks are found through tiles of 8³ bricks (64³ nodes): a dense table maps each tile to its
//! brick table or marks it absent, and a brick table maps each of its bricks to a stored brick or
//! marks it absent. A lookup is two table reads, whatever the grid's size, and memory is that of
//! the stored bricks plus 2 KiB per tile that holds any (the tile table is 4 bytes per 64³
//! nodes: 1 MB at 4000³). An absent brick's value is the background: one inside bit per absent
//! tile, and one per brick in the tiles that exist.

use rayon::prelude::*;

/// Nodes per brick edge.
pub const BRICK_EDGE: usize = 8;
const BRICK_SHIFT: u32 = BRICK_EDGE.trailing_zeros();
const BRICK_MASK: usize = BRICK_EDGE - 1;
/// Nodes in one brick, x fastest within it.
pub const BRICK_NODES: usize = BRICK_EDGE * BRICK_EDGE * BRICK_EDGE;

/// Bricks per tile edge.
const TILE_EDGE: usize = 8;
const TILE_SHIFT: u32 = TILE_EDGE.trailing_zeros();
const TILE_MASK: usize = TILE_EDGE - 1;
const TILE_BRICKS: usize = TILE_EDGE * TILE_EDGE * TILE_EDGE;

const ABSENT: u32 = u32::MAX;

/// The values of one brick, x fastest; nodes past the grid's last node are padding.
pub type BrickValues = [f32; BRICK_NODES];

/// The value of absent bricks, by side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Background {
    pub outside: f32,
    pub inside: f32,
}

impl Background {
    /// `+clamp` outside, `−clamp` inside: a distance field clamped to a band.
    pub fn clamp(clamp: f32) -> Self {
        Self {
            outside: clamp,
            inside: -clamp,
        }
    }

    /// The value of an absent brick on `inside`.
    #[inline]
    pub fn value(&self, inside: bool) -> f32 {
        if inside {
            self.inside
        } else {
            self.outside
        }
    }
}

/// The bricks of one tile that exist, and the side of the others.
#[derive(Clone, Debug)]
struct Tile {
    /// Per brick of the tile (x fastest): its index among the stored bricks, or `ABSENT`.
    slots: Box<[u32; TILE_BRICKS]>,
    /// Per brick, set when an absent brick is inside.
    inside: [u64; TILE_BRICKS / 64],
}

/// A grid of `dims` nodes stored as bricks of [`BRICK_EDGE`]³ nodes with a background.
#[derive(Clone)]
pub struct SparseGrid {
    dims: [usize; 3],
    brick_counts: [usize; 3],
    tile_counts: [usize; 3],
    /// Per tile: its index in `tiles`, or `ABSENT`.
    tile_slots: Vec<u32>,
    /// Per tile, set when an absent tile is inside.
    tile_inside: Vec<u64>,
    tiles: Vec<Tile>,
    /// Boxed so growing the list moves pointers, not 2 KiB per brick.
    #[allow(clippy::vec_box)]
    bricks: Vec<Box<BrickValues>>,
    /// Brick coordinates of `bricks`, in the same order.
    coords: Vec<[u32; 3]>,
    background: Background,
}

#[inline]
fn bit(words: &[u64], i: usize) -> bool {
    words[i >> 6] >> (i & 63) & 1 == 1
}

#[inline]
fn set_bit(words: &mut [u64], i: usize, on: bool) {
    let mask = 1u64 << (i & 63);
    if on {
        words[i >> 6] |= mask;
    } else {
        words[i >> 6] &= !mask;
    }
}

/// Position of node `n` within its brick.
#[inline]
pub fn brick_offset(n: [usize; 3]) -> usize {
    (n[0] & BRICK_MASK)
        | (n[1] & BRICK_MASK) << BRICK_SHIFT
        | (n[2] & BRICK_MASK) << (2 * BRICK_SHIFT)
}

/// The brick holding node `n`.
#[inline]
pub fn brick_of(n: [usize; 3]) -> [usize; 3] {
    n.map(|c| c >> BRICK_SHIFT)
}

impl SparseGrid {
    /// A grid with no stored brick, every node outside.
    ///
    /// # Panics
    /// When an axis has no node or so many bricks that their count overflows `u32` per axis.
    pub fn new(dims: [usize; 3], background: Background) -> Self {
        assert!(
            dims.iter().all(|&n| n > 0 && n < (1 << 30)),
            "bad dims {dims:?}"
        );
        let brick_counts = dims.map(|n| n.div_ceil(BRICK_EDGE));
        let tile_counts = brick_counts.map(|n| n.div_ceil(TILE_EDGE));
        let tiles: usize = tile_counts.iter().product();
        Self {
            dims,
            brick_counts,
            tile_counts,
            tile_slots: vec![ABSENT; tiles],
            tile_inside: vec![0; tiles.div_ceil(64)],
            tiles: Vec::new(),
            bricks: Vec::new(),
            coords: Vec::new(),
            background,
        }
    }

    /// Every node stored, from values in x-fastest order.
    ///
    /// # Panics
    /// When `values` does not hold one value per node.
    pub fn from_dense(dims: [usize; 3], values: &[f32], background: Background) -> Self {
        Self::from_dense_where(dims, values, background, |_| Some(true))
    }

    /// The bricks of `values` (x fastest) that `keep` asks for: `Some(true)` stores a brick,
    /// `Some(false)` leaves it outside and `None` inside.
    pub fn from_dense_where(
        dims: [usize; 3],
        values: &[f32],
        background: Background,
        mut keep: impl FnMut([usize; 3]) -> Option<bool>,
    ) -> Self {
        assert_eq!(values.len(), dims.iter().product::<usize>());
        let mut grid = Self::new(dims, background);
        let [nx, ny, _] = dims;
        for b in grid.all_bricks() {
            match keep(b) {
                Some(true) => {
                    let mut brick = Box::new([background.outside; BRICK_NODES]);
                    let (lo, n) = grid.brick_extent(b);
                    for k in 0..n[2] {
                        for j in 0..n[1] {
                            let src = lo[0] + nx * (lo[1] + j + ny * (lo[2] + k));
                            let dst = BRICK_EDGE * (j + BRICK_EDGE * k);
                            brick[dst..dst + n[0]].copy_from_slice(&values[src..src + n[0]]);
                        }
                    }
                    grid.insert(b, brick);
                }
                Some(false) => {}
                None => grid.set_inside(b, true),
            }
        }
        grid
    }

    /// Nodes per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Bricks per axis.
    pub fn brick_counts(&self) -> [usize; 3] {
        self.brick_counts
    }

    /// The value of absent bricks.
    pub fn background(&self) -> Background {
        self.background
    }

    /// Number of stored bricks.
    pub fn stored_count(&self) -> usize {
        self.bricks.len()
    }

    /// Whether every brick of the grid is stored.
    pub fn is_full(&self) -> bool {
        self.bricks.len() == self.brick_counts.iter().product::<usize>()
    }

    /// Bytes held, tables included.
    pub fn memory_bytes(&self) -> usize {
        self.bricks.len() * (size_of::<BrickValues>() + 8 + 12)
            + self.tiles.len() * (size_of::<[u32; TILE_BRICKS]>() + 64 + 8)
            + self.tile_slots.len() * 4
            + self.tile_inside.len() * 8
    }

    /// First node and node counts of brick `b` within the grid.
    pub fn brick_extent(&self, b: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        let lo = b.map(|c| c * BRICK_EDGE);
        let n = [0, 1, 2].map(|a| (lo[a] + BRICK_EDGE).min(self.dims[a]) - lo[a]);
        (lo, n)
    }

    /// Every brick coordinate, x fastest.
    pub fn all_bricks(&self) -> impl Iterator<Item = [usize; 3]> {
        let [bx, by, bz] = self.brick_counts;
        (0..bz).flat_map(move |k| (0..by).flat_map(move |j| (0..bx).map(move |i| [i, j, k])))
    }

    #[inline]
    fn tile_index(&self, b: [usize; 3]) -> usize {
        let t = b.map(|c| c >> TILE_SHIFT);
        t[0] + self.tile_counts[0] * (t[1] + self.tile_counts[1] * t[2])
    }

    #[inline]
    fn in_tile(b: [usize; 3]) -> usize {
        (b[0] & TILE_MASK)
            | (b[1] & TILE_MASK) << TILE_SHIFT
            | (b[2] & TILE_MASK) << (2 * TILE_SHIFT)
    }

    /// Index among the stored bricks of brick `b`, if stored.
    #[inline]
    fn slot(&self, b: [usize; 3]) -> Option<usize> {
        let t = self.tile_slots[self.tile_index(b)];
        if t == ABSENT {
            return None;
        }
        let s = self.tiles[t as usize].slots[Self::in_tile(b)];
        (s != ABSENT).then_some(s as usize)
    }

    /// Whether brick `b` is stored.
    pub fn is_stored(&self, b: [usize; 3]) -> bool {
        self.slot(b).is_some()
    }

    /// The stored values of brick `b`.
    #[inline]
    pub fn brick(&self, b: [usize; 3]) -> Option<&BrickValues> {
        self.slot(b).map(|s| &*self.bricks[s])
    }

    /// The stored values of brick `b`, to change in place.
    pub fn brick_mut(&mut self, b: [usize; 3]) -> Option<&mut BrickValues> {
        self.slot(b).map(|s| &mut *self.bricks[s])
    }

    /// Whether brick `b`, were it absent, would be inside.
    #[inline]
    pub fn is_inside(&self, b: [usize; 3]) -> bool {
        let ti = self.tile_index(b);
        let t = self.tile_slots[ti];
        if t == ABSENT {
            bit(&self.tile_inside, ti)
        } else {
            bit(&self.tiles[t as usize].inside, Self::in_tile(b))
        }
    }

    /// The end (at most `end`) of the run of bricks along x from `b` whose side, were they
    /// absent, is `b`'s ([`Self::is_inside`]): a tile without bricks is stepped over whole.
    pub fn same_side_end(&self, b: [usize; 3], end: usize) -> usize {
        let inside = self.is_inside(b);
        let mut x = b[0];
        while x < end {
            let at = [x, b[1], b[2]];
            let ti = self.tile_index(at);
            if self.tile_slots[ti] == ABSENT {
                if bit(&self.tile_inside, ti) != inside {
                    return x;
                }
                x = ((x >> TILE_SHIFT) + 1) << TILE_SHIFT;
            } else {
                if self.is_inside(at) != inside {
                    return x;
                }
                x += 1;
            }
        }
        end
    }

    /// The value every node of an absent brick `b` takes.
    #[inline]
    pub fn background_of(&self, b: [usize; 3]) -> f32 {
        self.background.value(self.is_inside(b))
    }

    /// The value at node `n`, which must lie in the grid.
    #[inline]
    pub fn get(&self, n: [usize; 3]) -> f32 {
        let b = brick_of(n);
        let ti = self.tile_index(b);
        let t = self.tile_slots[ti];
        if t == ABSENT {
            return self.background.value(bit(&self.tile_inside, ti));
        }
        let tile = &self.tiles[t as usize];
        let bt = Self::in_tile(b);
        let s = tile.slots[bt];
        if s == ABSENT {
            self.background.value(bit(&tile.inside, bt))
        } else {
            self.bricks[s as usize][brick_offset(n)]
        }
    }

    /// Copies the box of `n` nodes from node `lo` into `out` (x fastest), a row segment per
    /// brick crossed. The box must lie in the grid.
    pub fn gather(&self, lo: [usize; 3], n: [usize; 3], out: &mut [f32]) {
        crate::cpu::run(Gather {
            grid: self,
            lo,
            n,
            out,
        })
    }

    /// [`SparseGrid::gather`], inlined into both builds of its kernel.
    #[inline(always)]
    fn gather_here(&self, lo: [usize; 3], n: [usize; 3], out: &mut [f32]) {
        let total = n[0] * n[1] * n[2];
        debug_assert!(out.len() >= total);
        let mut at = 0;
        for k in lo[2]..lo[2] + n[2] {
            for j in lo[1]..lo[1] + n[1] {
                let mut i = lo[0];
                let end = lo[0] + n[0];
                while i < end {
                    let run = (BRICK_EDGE - (i & BRICK_MASK)).min(end - i);
                    let b = brick_of([i, j, k]);
                    match self.brick(b) {
                        Some(v) => {
                            let s = brick_offset([i, j, k]);
                            if s + BRICK_EDGE <= BRICK_NODES && at + BRICK_EDGE <= total {
                                // A copy of a brick edge's length wherever both sides have
                                // room, not a call per segment (small boxes, such as an edge's
                                // stencil, are mostly short segments). What it writes past the
                                // segment belongs to later segments of the box, which write it
                                // again.
                                let row: &[f32; BRICK_EDGE] =
                                    v[s..s + BRICK_EDGE].try_into().expect("a brick edge");
                                out[at..at + BRICK_EDGE].copy_from_slice(row);
                            } else {
                                out[at..at + run].copy_from_slice(&v[s..s + run]);
                            }
                        }
                        None => out[at..at + run].fill(self.background_of(b)),
                    }
                    at += run;
                    i += run;
                }
            }
        }
    }

    /// The value at flat index `i` (x fastest).
    pub fn get_index(&self, i: usize) -> f32 {
        let [nx, ny, _] = self.dims;
        self.get([i % nx, (i / nx) % ny, i / (nx * ny)])
    }

    /// The tile of brick `b`, created with the absent tile's side if missing.
    fn tile_mut(&mut self, b: [usize; 3]) -> &mut Tile {
        let ti = self.tile_index(b);
        if self.tile_slots[ti] == ABSENT {
            let side = if bit(&self.tile_inside, ti) {
                u64::MAX
            } else {
                0
            };
            self.tile_slots[ti] = self.tiles.len() as u32;
            self.tiles.push(Tile {
                slots: Box::new([ABSENT; TILE_BRICKS]),
                inside: [side; TILE_BRICKS / 64],
            });
        }
        let t = self.tile_slots[ti] as usize;
        &mut self.tiles[t]
    }

    /// Stores `values` as brick `b`, replacing what was there.
    pub fn insert(&mut self, b: [usize; 3], values: Box<BrickValues>) {
        if let Some(s) = self.slot(b) {
            self.bricks[s] = values;
            return;
        }
        let s = self.bricks.len() as u32;
        self.tile_mut(b).slots[Self::in_tile(b)] = s;
        self.bricks.push(values);
        self.coords.push(b.map(|c| c as u32));
    }

    /// The stored brick `b`, created filled with its background if absent.
    pub fn brick_or_background(&mut self, b: [usize; 3]) -> &mut BrickValues {
        if self.slot(b).is_none() {
            let v = self.background_of(b);
            self.insert(b, Box::new([v; BRICK_NODES]));
        }
        let s = self.slot(b).unwrap_or_default();
        &mut self.bricks[s]
    }

    /// Sets the side of brick `b` for when it is absent. A whole absent tile takes one bit, so
    /// marking regions inside stays cheap until a tile holds bricks of both sides.
    pub fn set_inside(&mut self, b: [usize; 3], inside: bool) {
        let ti = self.tile_index(b);
        if self.tile_slots[ti] == ABSENT {
            if bit(&self.tile_inside, ti) == inside {
                return;
            }
            if self.tile_is_uniform_region(b) {
                set_bit(&mut self.tile_inside, ti, inside);
                return;
            }
        }
        let bt = Self::in_tile(b);
        set_bit(&mut self.tile_mut(b).inside, bt, inside);
    }

    /// Whether the tile of `b` holds only `b`: a tile at a grid corner with one brick.
    fn tile_is_uniform_region(&self, b: [usize; 3]) -> bool {
        let t = b.map(|c| c >> TILE_SHIFT);
        (0..3).all(|a| {
            let first = t[a] << TILE_SHIFT;
            let last = ((t[a] + 1) << TILE_SHIFT).min(self.brick_counts[a]);
            last - first == 1
        })
    }

    /// Sets the side of a whole tile (the 8³ bricks around brick `b`) when it holds no brick.
    /// Returns false, doing nothing, if the tile exists.
    pub fn set_tile_inside(&mut self, b: [usize; 3], inside: bool) -> bool {
        let ti = self.tile_index(b);
        if self.tile_slots[ti] != ABSENT {
            return false;
        }
        set_bit(&mut self.tile_inside, ti, inside);
        true
    }

    /// Drops the tables of tiles that hold no brick and whose bricks are all on one side,
    /// leaving one bit for the tile.
    pub fn compact_tiles(&mut self) {
        let old = std::mem::take(&mut self.tiles);
        let mut kept = Vec::with_capacity(old.len());
        for ti in 0..self.tile_slots.len() {
            let t = self.tile_slots[ti];
            if t == ABSENT {
                continue;
            }
            let tile = &old[t as usize];
            let empty = tile.slots.iter().all(|&s| s == ABSENT);
            let side = tile.inside[0] & 1 == 1;
            let uniform = tile
                .inside
                .iter()
                .all(|&w| w == if side { u64::MAX } else { 0 });
            if empty && uniform {
                self.tile_slots[ti] = ABSENT;
                set_bit(&mut self.tile_inside, ti, side);
            } else {
                self.tile_slots[ti] = kept.len() as u32;
                kept.push(tile.clone());
            }
        }
        self.tiles = kept;
    }

    /// Stored bricks with their coordinates, in the order they were stored.
    pub fn stored(&self) -> impl ExactSizeIterator<Item = ([usize; 3], &BrickValues)> {
        self.coords
            .iter()
            .zip(&self.bricks)
            .map(|(c, v)| (c.map(|x| x as usize), &**v))
    }

    /// [`SparseGrid::stored`] as a parallel iterator, in the same order where it is collected.
    pub fn stored_par(&self) -> impl IndexedParallelIterator<Item = ([usize; 3], &BrickValues)> {
        self.coords
            .par_iter()
            .zip(&self.bricks)
            .map(|(c, v)| (c.map(|x| x as usize), &**v))
    }

    /// Whether some absent brick is inside, and whether some is outside: the values, at most
    /// two, that absent bricks take. Found tile by tile, so a grid of mostly absent bricks
    /// costs its tiles, not its bricks.
    pub fn absent_sides(&self) -> (bool, bool) {
        let (mut inside, mut outside) = (false, false);
        let [tx, ty, _] = self.tile_counts;
        for (ti, &slot) in self.tile_slots.iter().enumerate() {
            if inside && outside {
                break;
            }
            if slot == ABSENT {
                // Every tile holds at least one brick of the grid.
                if bit(&self.tile_inside, ti) {
                    inside = true;
                } else {
                    outside = true;
                }
                continue;
            }
            let tile = &self.tiles[slot as usize];
            let first = [ti % tx, ti / tx % ty, ti / (tx * ty)].map(|t| t * TILE_EDGE);
            let span = |a: usize| 0..TILE_EDGE.min(self.brick_counts[a] - first[a]);
            for k in span(2) {
                for j in span(1) {
                    for i in span(0) {
                        let at = Self::in_tile([i, j, k]);
                        if tile.slots[at] == ABSENT {
                            if bit(&tile.inside, at) {
                                inside = true;
                            } else {
                                outside = true;
                            }
                        }
                    }
                }
            }
        }
        (inside, outside)
    }

    /// A box of bricks (per axis, a range of brick indices) holding every stored brick and
    /// every absent brick inside; each brick outside it is absent and outside. Found tile by
    /// tile, so it costs the tiles, not the bricks; a tile holding any brick counts whole.
    /// Empty ranges when every brick is absent and outside.
    pub fn occupied_bricks(&self) -> [std::ops::Range<usize>; 3] {
        self.occupied_bricks_within(0..self.brick_counts[2])
    }

    /// [`Self::occupied_bricks`] among the brick layers `layers` along z: the bricks of the
    /// other layers are not looked at.
    pub fn occupied_bricks_within(
        &self,
        layers: std::ops::Range<usize>,
    ) -> [std::ops::Range<usize>; 3] {
        let [tx, ty, tz] = self.tile_counts;
        let tiles = (layers.start >> TILE_SHIFT).min(tz)..layers.end.div_ceil(TILE_EDGE).min(tz);
        let (mut lo, mut hi) = ([usize::MAX; 3], [0usize; 3]);
        let plane = tx * ty;
        for ti in tiles.start * plane..tiles.end * plane {
            if self.tile_slots[ti] == ABSENT && !bit(&self.tile_inside, ti) {
                continue;
            }
            let t = [ti % tx, ti / tx % ty, ti / (tx * ty)];
            for a in 0..3 {
                lo[a] = lo[a].min(t[a] * TILE_EDGE);
                hi[a] = hi[a].max(((t[a] + 1) * TILE_EDGE).min(self.brick_counts[a]));
            }
        }
        // Tiles straddle the asked layers: the box stays within them.
        lo[2] = lo[2].max(layers.start);
        hi[2] = hi[2].min(layers.end);
        if (0..3).any(|a| lo[a] >= hi[a]) {
            return [0..0, 0..0, 0..0];
        }
        std::array::from_fn(|a| lo[a]..hi[a])
    }

    /// Stored bricks, to change in place.
    pub fn stored_mut(&mut self) -> impl ExactSizeIterator<Item = ([usize; 3], &mut BrickValues)> {
        self.coords
            .iter()
            .zip(self.bricks.iter_mut())
            .map(|(c, v)| (c.map(|x| x as usize), &mut **v))
    }

    /// Brick `b`'s values, stored or background.
    pub fn brick_values(&self, b: [usize; 3]) -> BrickValues {
        match self.brick(b) {
            Some(v) => *v,
            None => [self.background_of(b); BRICK_NODES],
        }
    }

    /// Every node's value, x fastest.
    pub fn to_dense(&self) -> Vec<f32> {
        let [nx, ny, nz] = self.dims;
        let mut out = vec![0.0f32; nx * ny * nz];
        for b in self.all_bricks() {
            let (lo, n) = self.brick_extent(b);
            let brick = self.brick(b);
            let bg = self.background_of(b);
            for k in 0..n[2] {
                for j in 0..n[1] {
                    let dst = lo[0] + nx * (lo[1] + j + ny * (lo[2] + k));
                    let row = &mut out[dst..dst + n[0]];
                    match brick {
                        Some(v) => {
                            let src = BRICK_EDGE * (j + BRICK_EDGE * k);
                            row.copy_from_slice(&v[src..src + n[0]]);
                        }
                        None => row.fill(bg),
                    }
                }
            }
        }
        out
    }

    /// The smallest and largest node value.
    pub fn value_range(&self) -> [f32; 2] {
        let empty = [f32::INFINITY, f32::NEG_INFINITY];
        let widen = |r: [f32; 2], v: f32| [r[0].min(v), r[1].max(v)];
        // A least and a greatest value do not depend on the order they are taken in.
        let mut range = self
            .stored_par()
            .map(|(b, v)| {
                let (_, n) = self.brick_extent(b);
                let mut range = empty;
                for k in 0..n[2] {
                    for j in 0..n[1] {
                        let s = BRICK_EDGE * (j + BRICK_EDGE * k);
                        range = v[s..s + n[0]].iter().fold(range, |r, &x| widen(r, x));
                    }
                }
                range
            })
            .reduce(|| empty, |a, b| [a[0].min(b[0]), a[1].max(b[1])]);
        let (inside, outside) = self.absent_sides();
        for (absent, side) in [(inside, true), (outside, false)] {
            if absent {
                range = widen(range, self.background.value(side));
            }
        }
        range
    }

    /// Replaces the value of absent bricks.
    pub fn set_background(&mut self, background: Background) {
        self.background = background;
    }

    /// Applies `f` to every stored value and to the background.
    pub fn map_values(&mut self, f: impl Fn(f32) -> f32 + Sync) {
        for b in self.bricks.iter_mut() {
            for v in b.iter_mut() {
                *v = f(*v);
            }
        }
        self.background = Background {
            outside: f(self.background.outside),
            inside: f(self.background.inside),
        };
    }

    /// The grid with no stored brick, each brick on the side it would take were it absent:
    /// what `retain` keeping nothing leaves, without copying the bricks first.
    pub fn sides_only(&self) -> Self {
        SparseGrid {
            dims: self.dims,
            brick_counts: self.brick_counts,
            tile_counts: self.tile_counts,
            tile_slots: self.tile_slots.clone(),
            tile_inside: self.tile_inside.clone(),
            tiles: self
                .tiles
                .iter()
                .map(|t| Tile {
                    slots: Box::new([ABSENT; TILE_BRICKS]),
                    inside: t.inside,
                })
                .collect(),
            bricks: Vec::new(),
            coords: Vec::new(),
            background: self.background,
        }
    }

    /// Keeps the stored bricks for which `keep` is true; the others take their background.
    pub fn retain(&mut self, mut keep: impl FnMut([usize; 3], &BrickValues) -> bool) {
        let old_bricks = std::mem::take(&mut self.bricks);
        let old_coords = std::mem::take(&mut self.coords);
        for t in self.tiles.iter_mut() {
            t.slots.fill(ABSENT);
        }
        for (c, v) in old_coords.into_iter().zip(old_bricks) {
            let b = c.map(|x| x as usize);
            if keep(b, &v) {
                self.insert(b, v);
            }
        }
    }
}

impl std::fmt::Debug for SparseGrid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseGrid")
            .field("dims", &self.dims)
            .field("stored_bricks", &self.bricks.len())
            .field("tiles", &self.tiles.len())
            .field("background", &self.background)
            .finish()
    }
}

impl PartialEq for SparseGrid {
    /// Equal when every node holds the same value (bit for bit, so NaN equals NaN).
    fn eq(&self, other: &Self) -> bool {
        if self.dims != other.dims {
            return false;
        }
        self.all_bricks().all(|b| {
            let (_, n) = self.brick_extent(b);
            let (x, y) = (self.brick_values(b), other.brick_values(b));
            (0..n[2]).all(|k| {
                (0..n[1]).all(|j| {
                    let s = BRICK_EDGE * (j + BRICK_EDGE * k);
                    x[s..s + n[0]]
                        .iter()
                        .zip(&y[s..s + n[0]])
                        .all(|(a, b)| a.to_bits() == b.to_bits())
                })
            })
        })
    }
}

/// [`SparseGrid::gather`] as a kernel: the fit's windows and the decode's stencils.
struct Gather<'a> {
    grid: &'a SparseGrid,
    lo: [usize; 3],
    n: [usize; 3],
    out: &'a mut [f32],
}

impl crate::cpu::Kernel for Gather<'_> {
    type Output = ();
    #[inline(always)]
    fn run(self) {
        self.grid.gather_here(self.lo, self.n, self.out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense(dims: [usize; 3]) -> Vec<f32> {
        (0..dims.iter().product::<usize>())
            .map(|i| i as f32 * 0.5 - 7.0)
            .collect()
    }

    #[test]
    fn dense_round_trip_keeps_every_node_on_odd_sizes() {
        for dims in [[1, 1, 1], [9, 3, 17], [8, 8, 8], [70, 5, 66]] {
            let v = dense(dims);
            let g = SparseGrid::from_dense(dims, &v, Background::clamp(1.0));
            assert!(g.is_full());
            assert_eq!(g.to_dense(), v, "{dims:?}");
            let [nx, ny, _] = dims;
            for n in [
                [0, 0, 0],
                [dims[0] - 1, dims[1] - 1, dims[2] - 1],
                [dims[0] / 2, 0, dims[2] / 3],
            ] {
                assert_eq!(g.get(n), v[n[0] + nx * (n[1] + ny * n[2])]);
            }
        }
    }

    /// The sides of the absent bricks and the value range, brick by brick.
    fn by_bricks(g: &SparseGrid) -> ((bool, bool), [f32; 2]) {
        let absent: Vec<bool> = g
            .all_bricks()
            .filter(|&b| !g.is_stored(b))
            .map(|b| g.is_inside(b))
            .collect();
        let values = g.to_dense();
        let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let sides = (absent.contains(&true), absent.contains(&false));
        (sides, [lo, hi])
    }

    #[test]
    fn absent_sides_and_range_are_those_of_every_brick() {
        // Brick counts that tiles divide and do not; sides from whole tiles and single bricks.
        for dims in [[130, 70, 9], [64, 64, 64], [9, 200, 17]] {
            let mut g = SparseGrid::new(dims, Background::clamp(2.0));
            let counts = g.brick_counts();
            let last = counts.map(|c| c - 1);
            assert_eq!(by_bricks(&g).0, (false, true));
            assert_eq!((g.absent_sides(), g.value_range()), by_bricks(&g));
            g.set_inside(last, true);
            assert_eq!((g.absent_sides(), g.value_range()), by_bricks(&g));
            g.insert(last, Box::new([0.5; BRICK_NODES]));
            assert_eq!((g.absent_sides(), g.value_range()), by_bricks(&g));
            // Every brick stored but one, inside: only the inside remains.
            for b in g.all_bricks().collect::<Vec<_>>() {
                if b != [0, 0, 0] {
                    g.insert(b, Box::new([b[0] as f32 - 1.5; BRICK_NODES]));
                }
            }
            g.set_inside([0, 0, 0], true);
            assert_eq!(by_bricks(&g).0, (true, false));
            assert_eq!((g.absent_sides(), g.value_range()), by_bricks(&g));
        }
    }

    #[test]
    fn side_runs_and_the_occupied_box_are_those_of_every_brick() {
        // 40 bricks along x (5 tiles), 9 along y: whole tiles inside, single bricks inside,
        // a stored brick (inside or not).
        let dims = [320, 72, 40];
        let mut g = SparseGrid::new(dims, Background::clamp(1.0));
        assert_eq!(g.occupied_bricks(), [0..0, 0..0, 0..0]);
        assert!(g.set_tile_inside([17, 1, 0], true));
        g.set_inside([30, 1, 0], true);
        g.set_inside([31, 1, 0], true);
        g.insert([33, 1, 0], Box::new([0.0; BRICK_NODES]));
        g.set_inside([33, 1, 0], true);
        g.set_inside([3, 8, 4], true);
        let counts = g.brick_counts();
        for b in g.all_bricks() {
            for end in [b[0] + 1, b[0] + 9, counts[0]] {
                let end = end.min(counts[0]);
                let side = g.is_inside(b);
                let want = (b[0]..end)
                    .find(|&x| g.is_inside([x, b[1], b[2]]) != side)
                    .unwrap_or(end);
                assert_eq!(g.same_side_end(b, end), want, "{b:?} to {end}");
            }
        }
        // Tiles 0 and 2..4 along x, 0 and 1 along y, 0 along z: the box of the tiles.
        assert_eq!(g.occupied_bricks(), [0..40, 0..9, 0..5]);
        assert_eq!(g.occupied_bricks_within(1..3), [0..40, 0..9, 1..3]);
        assert_eq!(g.occupied_bricks_within(5..9), [0..0, 0..0, 0..0]);
    }

    #[test]
    fn absent_bricks_take_their_side_background() {
        let dims = [130, 70, 9];
        let mut g = SparseGrid::new(dims, Background::clamp(2.0));
        assert_eq!(g.get([129, 69, 8]), 2.0);
        // A whole tile inside, then one brick of it stored: the rest of the tile stays inside.
        assert!(g.set_tile_inside([9, 1, 0], true));
        assert_eq!(g.get([70, 10, 3]), -2.0);
        g.insert([8, 0, 0], Box::new([5.0; BRICK_NODES]));
        assert_eq!(g.get([64, 0, 0]), 5.0);
        assert_eq!(g.get([80, 10, 3]), -2.0);
        g.set_inside([10, 0, 0], false);
        assert_eq!(g.get([80, 0, 0]), 2.0);
        assert_eq!(g.get([88, 0, 0]), -2.0);
        assert_eq!(g.get([0, 0, 0]), 2.0);
        assert_eq!(g.stored_count(), 1);
        g.retain(|_, _| false);
        assert_eq!(g.get([64, 0, 0]), -2.0);
    }

    #[test]
    fn gathered_boxes_match_the_dense_values() {
        let dims = [21, 19, 18];
        let v = dense(dims);
        let mut g = SparseGrid::from_dense(dims, &v, Background::clamp(1.0));
        g.retain(|b, _| b != [1, 1, 1]);
        let mut want = v.clone();
        for k in 8..16 {
            for j in 8..16 {
                for i in 8..16 {
                    want[i + 21 * (j + 19 * k)] = 1.0;
                }
            }
        }
        // Boxes across bricks, inside one, an edge's stencil, single rows and nodes, and boxes
        // reaching the grid's last node on each axis.
        let boxes = [
            ([3, 5, 6], [15, 4, 11]),
            ([9, 9, 9], [4, 3, 3]),
            ([6, 7, 2], [3, 4, 3]),
            ([0, 0, 0], [21, 19, 18]),
            ([13, 2, 9], [8, 1, 1]),
            ([17, 15, 14], [4, 4, 4]),
            ([20, 18, 17], [1, 1, 1]),
            ([1, 10, 3], [7, 9, 2]),
            // A whole brick (of 8³), part of one at the grid's end, and whole brick rows along
            // x across stored and absent bricks.
            ([0, 0, 0], [8, 8, 8]),
            ([16, 2, 3], [5, 6, 5]),
            ([0, 0, 0], [16, 16, 16]),
            ([8, 3, 1], [8, 9, 17]),
        ];
        for (lo, n) in boxes {
            // Room past the box, which the gather must leave as it was.
            let total = n[0] * n[1] * n[2];
            let mut out = vec![-7.0; total + 9];
            g.gather(lo, n, &mut out);
            let mut at = 0;
            for k in lo[2]..lo[2] + n[2] {
                for j in lo[1]..lo[1] + n[1] {
                    for i in lo[0]..lo[0] + n[0] {
                        assert_eq!(
                            out[at],
                            want[i + 21 * (j + 19 * k)],
                            "{lo:?} {n:?}: {i} {j} {k}"
                        );
                        at += 1;
                    }
                }
            }
            assert!(out[total..].iter().all(|&x| x == -7.0), "{lo:?} {n:?}");
        }
    }

    #[test]
    fn equality_is_by_value_not_by_storage() {
        let dims = [20, 20, 20];
        let mut a = SparseGrid::new(dims, Background::clamp(1.0));
        let b = a.clone();
        a.insert([1, 1, 1], Box::new([3.0; BRICK_NODES]));
        assert_ne!(a, b);
        a.insert([1, 1, 1], Box::new([3.0; BRICK_NODES]));
        let mut c = SparseGrid::new(dims, Background::clamp(1.0));
        *c.brick_or_background([1, 1, 1]) = [3.0; BRICK_NODES];
        assert_eq!(a, c);
        let full = SparseGrid::from_dense(dims, &a.to_dense(), Background::clamp(1.0));
        assert_eq!(a, full);
    }
}
