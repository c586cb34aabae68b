//! The coefficient bricks a layer reads, one brick layer at a time, and where they come from.

use pgvol_core::sparse::BrickValues;
use pgvol_core::{SparseGrid, WordScale, BRICK_EDGE, BRICK_NODES};

use crate::SliceError;

/// A brick's values, borrowed from a grid held in memory or decoded from a file, or a file's
/// 16-bit words with the scale that maps them to values (exactly, for every such word): half
/// the memory of the values, for the same coefficients.
pub enum BrickRef<'a> {
    Borrowed(&'a BrickValues),
    Owned(Box<BrickValues>),
    Words(Box<[i16; BRICK_NODES]>, WordScale),
}

impl BrickRef<'_> {
    /// Adds `weight` times values `start..start + out.len()` (x fastest) to `out`.
    // Always inlined: the plane collapse kernel's AVX2 build must hold it.
    #[inline(always)]
    pub(crate) fn add_run(&self, start: usize, weight: f32, out: &mut [f32]) {
        let end = start + out.len();
        match self {
            BrickRef::Borrowed(values) => add_values(&values[start..end], weight, out),
            BrickRef::Owned(values) => add_values(&values[start..end], weight, out),
            BrickRef::Words(words, scale) => scale.add_words(&words[start..end], weight, out),
        }
    }

    /// Adds `weight` times values `start`, `start + stride`, ... (x fastest) to `out`.
    // Always inlined: the plane collapse kernel's AVX2 build must hold it.
    #[inline(always)]
    pub(crate) fn add_strided(&self, start: usize, stride: usize, weight: f32, out: &mut [f32]) {
        let at = |k: usize| start + k * stride;
        match self {
            BrickRef::Borrowed(values) => add_each(out, weight, |k| values[at(k)]),
            BrickRef::Owned(values) => add_each(out, weight, |k| values[at(k)]),
            BrickRef::Words(words, scale) => {
                add_each(out, weight, |k| scale.value(words[at(k)] as i32))
            }
        }
    }

    /// Per node layer along grid axis `axis`: the least and greatest value.
    pub fn layer_ranges(&self, axis: usize) -> LayerRanges {
        pgvol_core::cpu::run(Ranges(self, axis))
    }

    /// [`BrickRef::layer_ranges`], inlined into both builds of its kernel.
    #[inline(always)]
    fn layer_ranges_here(&self, axis: usize) -> LayerRanges {
        match self {
            BrickRef::Borrowed(values) => ranges_of(axis, |i| values[i]),
            BrickRef::Owned(values) => ranges_of(axis, |i| values[i]),
            BrickRef::Words(words, scale) => {
                // A word's value grows with the word, so the extreme words give the extremes.
                word_ranges(axis, words).map(|r| r.map(|w| scale.value(w as i32)))
            }
        }
    }
}

/// [`BrickRef::layer_ranges`] as a kernel: every brick a slicing loads goes through it.
struct Ranges<'r, 'a>(&'r BrickRef<'a>, usize);

impl pgvol_core::cpu::Kernel for Ranges<'_, '_> {
    type Output = LayerRanges;
    #[inline(always)]
    fn run(self) -> LayerRanges {
        self.0.layer_ranges_here(self.1)
    }
}

/// [`BrickRef::layer_ranges`] of 16-bit words: per node layer, the least and greatest word.
#[inline(always)]
fn word_ranges(axis: usize, words: &[i16; BRICK_NODES]) -> [[i16; 2]; BRICK_EDGE] {
    let mut lo = [i16::MAX; BRICK_EDGE];
    let mut hi = [i16::MIN; BRICK_EDGE];
    for (row, run) in words.chunks_exact(BRICK_EDGE).enumerate() {
        // Row `row` runs along x at y = row % E, z = row / E.
        if axis == 0 {
            for (x, &w) in run.iter().enumerate() {
                lo[x] = lo[x].min(w);
                hi[x] = hi[x].max(w);
            }
        } else {
            let at = if axis == 1 {
                row % BRICK_EDGE
            } else {
                row / BRICK_EDGE
            };
            lo[at] = run.iter().fold(lo[at], |a, &w| a.min(w));
            hi[at] = run.iter().fold(hi[at], |a, &w| a.max(w));
        }
    }
    std::array::from_fn(|n| [lo[n], hi[n]])
}

#[inline(always)]
fn add_each(out: &mut [f32], weight: f32, value: impl Fn(usize) -> f32) {
    for (k, o) in out.iter_mut().enumerate() {
        *o += weight * value(k);
    }
}

/// [`BrickRef::layer_ranges`] of the values `value(i)`, x fastest.
#[inline(always)]
fn ranges_of(axis: usize, value: impl Fn(usize) -> f32) -> [[f32; 2]; BRICK_EDGE] {
    let mut ranges = [[f32::INFINITY, f32::NEG_INFINITY]; BRICK_EDGE];
    for row in 0..BRICK_NODES / BRICK_EDGE {
        // Row `row` runs along x at y = row % E, z = row / E.
        let at = [0, row % BRICK_EDGE, row / BRICK_EDGE];
        for x in 0..BRICK_EDGE {
            let v = value(row * BRICK_EDGE + x);
            let r = &mut ranges[if axis == 0 { x } else { at[axis] }];
            if v < r[0] {
                r[0] = v;
            }
            if v > r[1] {
                r[1] = v;
            }
        }
    }
    ranges
}

#[inline(always)]
fn add_values(values: &[f32], weight: f32, out: &mut [f32]) {
    for (o, x) in out.iter_mut().zip(values) {
        *o += weight * x;
    }
}

/// Per node layer of a brick along a layer's axis: its least and greatest value.
pub type LayerRanges = [[f32; 2]; BRICK_EDGE];

/// A brick layer's entry for an absent brick outside.
pub const OUTSIDE: u32 = u32::MAX;
/// A brick layer's entry for an absent brick inside.
pub const INSIDE: u32 = u32::MAX - 1;

/// The bricks of a grid whose coordinate along one axis is fixed: per brick position in the
/// plane of the two other axes (the first of them fastest, in the axes' cyclic order), the index
/// of its values in `bricks`, or [`OUTSIDE`] / [`INSIDE`] for an absent brick.
pub struct BrickLayer<'a> {
    /// Brick positions along each of the plane's axes.
    counts: [usize; 2],
    states: Vec<u32>,
    /// The positions whose state is not [`OUTSIDE`], in the order they were set.
    occupied: Vec<u32>,
    /// The stored positions and those of another kind (outside, inside, stored) than one of
    /// their four neighbours, ascending; set by [`BrickLayer::finish`].
    boundary: Vec<u32>,
    pub bricks: Vec<BrickRef<'a>>,
    /// Per brick in `bricks`, per node layer along the layer's axis: its least and greatest
    /// value.
    pub ranges: Vec<LayerRanges>,
}

impl<'a> BrickLayer<'a> {
    /// A layer of `counts[0] × counts[1]` brick positions, every brick absent and outside.
    pub fn outside(counts: [usize; 2]) -> Self {
        BrickLayer {
            counts,
            states: vec![OUTSIDE; counts[0] * counts[1]],
            occupied: Vec::new(),
            boundary: Vec::new(),
            bricks: Vec::new(),
            ranges: Vec::new(),
        }
    }

    /// Marks the absent brick at position `at` inside.
    pub fn set_inside(&mut self, at: usize) {
        if self.states[at] == OUTSIDE {
            self.occupied.push(at as u32);
        }
        self.states[at] = INSIDE;
    }

    /// The state of position `at`: an index in `bricks`, [`INSIDE`] or [`OUTSIDE`].
    #[inline]
    pub fn state(&self, at: usize) -> u32 {
        self.states[at]
    }

    /// The positions that are not absent and outside, ascending once [`BrickLayer::finish`]
    /// has run.
    pub fn occupied(&self) -> &[u32] {
        &self.occupied
    }

    /// The stored positions and those whose kind (absent outside, absent inside, stored)
    /// differs from one of their four neighbours', ascending, once [`BrickLayer::finish`] has
    /// run. Away from them the layer is the same absent kind over whole regions, which a plane
    /// need not visit brick by brick.
    pub fn boundary(&self) -> &[u32] {
        &self.boundary
    }

    /// Sorts the occupied positions and finds the boundary; to be called once every brick is
    /// set.
    pub fn finish(mut self) -> Self {
        self.occupied.sort_unstable();
        let kind = |s: u32| match s {
            OUTSIDE => 0u8,
            INSIDE => 1,
            _ => 2,
        };
        let mut boundary = Vec::new();
        for &k in &self.occupied {
            let k = k as usize;
            let own = kind(self.states[k]);
            let mut differs = own == 2;
            for n in beside(k, self.counts).into_iter().flatten() {
                let theirs = kind(self.states[n]);
                differs |= theirs != own;
                // An outside neighbour is never visited from its own entry.
                if theirs == 0 {
                    boundary.push(n as u32);
                }
            }
            if differs {
                boundary.push(k as u32);
            }
        }
        boundary.sort_unstable();
        boundary.dedup();
        self.boundary = boundary;
        self
    }

    /// Stores `values` at brick position `at` of a layer across grid axis `axis`.
    pub fn insert(&mut self, at: usize, values: BrickRef<'a>, axis: usize) {
        let ranges = values.layer_ranges(axis);
        self.insert_ranged(at, values, ranges);
    }

    /// [`BrickLayer::insert`] with the ranges [`BrickRef::layer_ranges`] gives, worked out
    /// beforehand (by a caller that computes many at once, in parallel).
    pub fn insert_ranged(&mut self, at: usize, values: BrickRef<'a>, ranges: LayerRanges) {
        if self.states[at] == OUTSIDE {
            self.occupied.push(at as u32);
        }
        self.states[at] = self.bricks.len() as u32;
        self.ranges.push(ranges);
        self.bricks.push(values);
    }
}

/// Brick layers of a coefficient grid along an axis, handed out in slabs of consecutive layers.
/// Slicing asks for the slabs its layers' supports reach, in increasing order, and keeps only a
/// window of them, so a source that decodes slabs on demand bounds memory by that window.
pub trait BrickSource: Sync {
    /// Why a slab could not be had (a damaged file, say).
    type Error: From<SliceError> + Send;

    /// Brick layers per slab.
    fn slab_bricks(&self) -> usize;

    /// The brick layers of slab `slab` along grid axis `axis` (0, 1 or 2), in order; positions
    /// within a layer as [`BrickLayer`] says. The last slab may hold fewer.
    fn slab(&self, axis: usize, slab: usize) -> Result<Vec<BrickLayer<'_>>, Self::Error>;
}

/// The four neighbours of position `k` in a plane of `counts` positions (the first axis
/// fastest) that lie in it: +u, +v, −u, −v.
#[inline]
pub(crate) fn beside(k: usize, counts: [usize; 2]) -> [Option<usize>; 4] {
    let [cu, cv] = counts;
    let (u, v) = (k % cu, k / cu);
    [
        (u + 1 < cu).then(|| k + 1),
        (v + 1 < cv).then(|| k + cu),
        (u > 0).then(|| k - 1),
        (v > 0).then(|| k - cu),
    ]
}

/// The axes of a brick layer's plane: the two after `axis` in cyclic order.
pub fn plane_axes(axis: usize) -> [usize; 2] {
    [(axis + 1) % 3, (axis + 2) % 3]
}

/// Brick counts of a grid of `dims` nodes.
pub fn brick_counts(dims: [usize; 3]) -> [usize; 3] {
    dims.map(|n| n.div_ceil(BRICK_EDGE))
}

/// A sparse grid held in memory, one brick layer per slab, its bricks borrowed.
impl BrickSource for SparseGrid {
    type Error = SliceError;

    fn slab_bricks(&self) -> usize {
        1
    }

    fn slab(&self, axis: usize, slab: usize) -> Result<Vec<BrickLayer<'_>>, SliceError> {
        let counts = self.brick_counts();
        let [b, c] = plane_axes(axis);
        let mut layer = BrickLayer::outside([counts[b], counts[c]]);
        for jc in 0..counts[c] {
            for jb in 0..counts[b] {
                let mut at = [0; 3];
                (at[axis], at[b], at[c]) = (slab, jb, jc);
                let k = jb + counts[b] * jc;
                match self.brick(at) {
                    Some(values) => layer.insert(k, BrickRef::Borrowed(values), axis),
                    None if self.is_inside(at) => layer.set_inside(k),
                    None => {}
                }
            }
        }
        Ok(vec![layer.finish()])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_boundary_holds_every_stored_brick_and_every_change_of_kind() {
        let counts = [9, 7];
        let values: Box<BrickValues> = Box::new([0.5; BRICK_NODES]);
        // A few patterns of inside regions and stored bricks, from a fixed pseudo-random walk.
        for seed in 0..20u64 {
            let mut layer = BrickLayer::outside(counts);
            let mut x = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            for at in 0..counts[0] * counts[1] {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
                match x >> 61 {
                    0..=2 => {}
                    3..=5 => layer.set_inside(at),
                    _ => layer.insert(at, BrickRef::Borrowed(&values), 2),
                }
            }
            let layer = layer.finish();
            // Stored bricks differ from each other here too, which changes nothing: they are
            // all on the boundary.
            let kind = |k: usize| layer.state(k);
            let boundary = layer.boundary();
            assert!(
                boundary.windows(2).all(|w| w[0] < w[1]),
                "ascending, no repeats"
            );
            for k in 0..counts[0] * counts[1] {
                let (u, v) = (k % counts[0], k / counts[0]);
                // The neighbours written out, not through `beside`, which `finish` uses.
                let neighbours = [
                    (u + 1 < counts[0]).then(|| k + 1),
                    (v + 1 < counts[1]).then(|| k + counts[0]),
                    (u > 0).then(|| k - 1),
                    (v > 0).then(|| k - counts[0]),
                ];
                let stored = layer.state(k) < INSIDE;
                let changes = neighbours.into_iter().flatten().any(|n| kind(n) != kind(k));
                assert_eq!(
                    boundary.binary_search(&(k as u32)).is_ok(),
                    stored || changes,
                    "seed {seed}, position {k}"
                );
            }
        }
    }

    #[test]
    fn word_bricks_range_as_their_values_do() {
        let scale = WordScale::new(0.01, 300, 8);
        // Words spread over both signs and both sides of the knee, in no order.
        let words: Box<[i16; BRICK_NODES]> = Box::new(std::array::from_fn(|i| {
            ((i as i64 * 7919 % 1201) - 600) as i16 * 27
        }));
        let values: Box<BrickValues> =
            Box::new(std::array::from_fn(|i| scale.value(words[i] as i32)));
        let as_words = BrickRef::Words(words, scale);
        let as_values = BrickRef::Owned(values);
        for axis in 0..3 {
            let (got, want) = (as_words.layer_ranges(axis), as_values.layer_ranges(axis));
            assert_eq!(got, want, "axis {axis}");
            assert!(want.iter().all(|r| r[0] < 0.0 && r[1] > 0.0));
        }
    }
}
