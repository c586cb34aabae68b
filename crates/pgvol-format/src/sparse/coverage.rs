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
}

impl Coverage {
    /// Every file brick.
    pub(crate) fn new(coeffs: &SparseGrid, bricks: &Bricks) -> Coverage {
        Coverage::layers(coeffs, bricks, 0..bricks.count[2])
    }

    /// The file bricks of the layers `layers` along z (clipped to the grid), reading only the
    /// grid's brick tables there, so a writer holding a window of layers can ask for them.
    pub(crate) fn layers(coeffs: &SparseGrid, bricks: &Bricks, layers: Range<usize>) -> Coverage {
        let per_layer = bricks.count[0] * bricks.count[1];
        let end = layers.end.min(bricks.count[2]);
        let first = layers.start.min(end) * per_layer;
        let flags = (first..end * per_layer)
            .into_par_iter()
            .map(|b| file_brick_flags(coeffs, bricks, b))
            .collect();
        Coverage { first, flags }
    }

    #[inline]
    pub(crate) fn flags(&self, b: usize) -> u8 {
        self.flags[b - self.first]
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
}
