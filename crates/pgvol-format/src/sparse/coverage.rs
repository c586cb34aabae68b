//! What each file brick covers of the sparse coefficient grid: whether any of its grid bricks
//! is stored, and which background sides the others take. One byte per file brick, found from
//! the grid's brick tables without reading a node, so that the band search can skip uniform
//! background and unstored file bricks get their side without a pass over their nodes.

use std::ops::Range;

use pgvol_core::{SparseGrid, BRICK_EDGE};
use rayon::prelude::*;

use super::bricks::Bricks;

/// A grid brick overlapping the file brick is stored.
pub(crate) const STORED: u8 = 1;
/// An unstored grid brick overlapping it is outside.
pub(crate) const OUTSIDE: u8 = 2;
/// An unstored grid brick overlapping it is inside.
pub(crate) const INSIDE: u8 = 4;
/// More of its nodes lie in unstored inside grid bricks than in unstored outside ones.
pub(crate) const MORE_INSIDE: u8 = 8;
/// More of its nodes lie in unstored outside grid bricks than in unstored inside ones.
pub(crate) const MORE_OUTSIDE: u8 = 16;

/// Per file brick of a range of layers along z, a set of the flags above.
pub(crate) struct Coverage {
    /// Index of the first file brick covered.
    first: usize,
    flags: Vec<u8>,
    /// A box of file bricks (per axis, a range) outside which every file brick covered is
    /// [`ALL_OUTSIDE`]; empty ranges when all are.
    occupied: [Range<usize>; 3],
}

/// The flags of a file brick whose grid bricks are all unstored and outside.
pub(crate) const ALL_OUTSIDE: u8 = OUTSIDE | MORE_OUTSIDE;

impl Coverage {
    /// Every file brick.
    pub(crate) fn new(coeffs: &SparseGrid, bricks: &Bricks) -> Coverage {
        Coverage::layers(coeffs, bricks, 0..bricks.count[2])
    }

    /// The file bricks of the layers `layers` along z (clipped to the grid), reading only the
    /// grid's brick tables there, so a writer holding a window of layers can ask for them.
    /// Only the file bricks overlapping the grid's occupied box are looked at
    /// ([`SparseGrid::occupied_bricks_within`]), so a small part on a large grid costs its box.
    pub(crate) fn layers(coeffs: &SparseGrid, bricks: &Bricks, layers: Range<usize>) -> Coverage {
        let per_layer = bricks.count[0] * bricks.count[1];
        let end = layers.end.min(bricks.count[2]);
        let start = layers.start.min(end);
        let first = start * per_layer;
        let e = bricks.edge;
        // Grid brick layers overlapping the file brick layers.
        let grid_layers = start * e / BRICK_EDGE..(end * e).div_ceil(BRICK_EDGE);
        let grid_box = coeffs.occupied_bricks_within(grid_layers);
        let occupied: [Range<usize>; 3] = std::array::from_fn(|a| {
            let r = &grid_box[a];
            if r.is_empty() {
                return 0..0;
            }
            let lo = r.start * BRICK_EDGE / e;
            let hi = (r.end * BRICK_EDGE).div_ceil(e).min(bricks.count[a]);
            let (lo, hi) = if a == 2 {
                (lo.max(start), hi.min(end))
            } else {
                (lo, hi)
            };
            if lo < hi {
                lo..hi
            } else {
                0..0
            }
        });
        let mut flags = vec![ALL_OUTSIDE; (end - start) * per_layer];
        if occupied.iter().all(|r| !r.is_empty()) {
            let [xs, ys, zs] = occupied.clone();
            flags
                .par_chunks_mut(per_layer)
                .enumerate()
                .filter(|(k, _)| zs.contains(&(start + k)))
                .for_each(|(k, layer)| {
                    for j in ys.clone() {
                        for i in xs.clone() {
                            let b = i + bricks.count[0] * j;
                            layer[b] =
                                file_brick_flags(coeffs, bricks, (start + k) * per_layer + b);
                        }
                    }
                });
        }
        Coverage {
            first,
            flags,
            occupied,
        }
    }

    #[inline]
    pub(crate) fn flags(&self, b: usize) -> u8 {
        self.flags[b - self.first]
    }

    /// The box of file bricks outside which every covered one is [`ALL_OUTSIDE`].
    pub(crate) fn occupied(&self) -> &[Range<usize>; 3] {
        &self.occupied
    }
}

fn file_brick_flags(coeffs: &SparseGrid, bricks: &Bricks, b: usize) -> u8 {
    let (lo, n) = bricks.extent(b);
    let first = lo.map(|c| c / BRICK_EDGE);
    let last = [0, 1, 2].map(|a| (lo[a] + n[a] - 1) / BRICK_EDGE);
    // Nodes of the file brick within grid brick `g` along one axis.
    let overlap = |a: usize, g: usize| {
        let from = lo[a].max(g * BRICK_EDGE);
        let to = (lo[a] + n[a]).min((g + 1) * BRICK_EDGE);
        to - from
    };
    let mut flags = 0;
    let (mut inside, mut outside) = (0usize, 0usize);
    for gk in first[2]..=last[2] {
        for gj in first[1]..=last[1] {
            for gi in first[0]..=last[0] {
                let g = [gi, gj, gk];
                if coeffs.is_stored(g) {
                    flags |= STORED;
                    continue;
                }
                let nodes = overlap(0, gi) * overlap(1, gj) * overlap(2, gk);
                if coeffs.is_inside(g) {
                    flags |= INSIDE;
                    inside += nodes;
                } else {
                    flags |= OUTSIDE;
                    outside += nodes;
                }
            }
        }
    }
    if inside > outside {
        flags |= MORE_INSIDE;
    } else if outside > inside {
        flags |= MORE_OUTSIDE;
    }
    flags
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_core::{Background, BRICK_NODES};

    #[test]
    fn flags_follow_the_grid_bricks_each_file_brick_overlaps() {
        // File bricks of 12 over grid bricks of 8: file brick 1 along x covers nodes 12..24,
        // half of grid brick 1 and all of grid brick 2.
        let mut g = SparseGrid::new([30, 8, 8], Background::clamp(1.0));
        g.set_inside([1, 0, 0], true);
        g.insert([3, 0, 0], Box::new([0.0; BRICK_NODES]));
        let bricks = Bricks::new([30, 8, 8], 12);
        let c = Coverage::new(&g, &bricks);
        // Nodes 0..12: 8 outside, 4 inside.
        assert_eq!(c.flags(0), OUTSIDE | INSIDE | MORE_OUTSIDE);
        // Nodes 12..24: 4 inside, 8 outside.
        assert_eq!(c.flags(1), OUTSIDE | INSIDE | MORE_OUTSIDE);
        // Nodes 24..30: grid brick 3, stored.
        assert_eq!(c.flags(2), STORED);
        g.set_inside([2, 0, 0], true);
        let c = Coverage::new(&g, &bricks);
        assert_eq!(c.flags(1), INSIDE | MORE_INSIDE);
    }

    #[test]
    fn bricks_beyond_the_occupied_box_are_all_outside_and_the_rest_looked_at() {
        // A small part far from the origin of a 600³ grid (75 grid bricks, 10 tiles per axis):
        // stored and inside bricks in one tile, file bricks of 12 nodes.
        let dims = [600; 3];
        let mut g = SparseGrid::new(dims, Background::clamp(1.0));
        g.insert([50, 51, 52], Box::new([0.0; BRICK_NODES]));
        g.set_inside([51, 51, 52], true);
        g.set_inside([52, 50, 53], true);
        let bricks = Bricks::new(dims, 12);
        for layers in [0..bricks.count[2], 30..40, 0..20] {
            let c = Coverage::layers(&g, &bricks, layers.clone());
            let per_layer = bricks.count[0] * bricks.count[1];
            let first = layers.start * per_layer;
            let mut looked_at = 0;
            for b in first..layers.end * per_layer {
                let want = file_brick_flags(&g, &bricks, b);
                assert_eq!(c.flags(b), want, "file brick {b} of layers {layers:?}");
                looked_at += usize::from(want != ALL_OUTSIDE);
            }
            let boxed: usize = c.occupied().iter().map(|r| r.len()).product();
            if layers.contains(&35) {
                // A tile of 8 grid bricks is 64 nodes, at most 7 file bricks across: the box
                // is the tile's, not the grid's 50³ file bricks.
                assert!(looked_at > 0 && boxed <= 7 * 7 * 7, "{:?}", c.occupied());
            } else {
                assert_eq!(looked_at, 0);
            }
        }
    }
}
