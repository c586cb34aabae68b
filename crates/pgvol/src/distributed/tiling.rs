//! Checking that an encode's parts arrive in plan order and tile the grid: z slabs in turn,
//! each cut into rows along y from y = 0.

use std::ops::Range;

use crate::error::{Error, Result};

/// Where the next part must start, in grid bricks.
pub(crate) struct Tiling {
    counts: [usize; 3],
    next_y: usize,
    next_z: usize,
    slab_end: usize,
}

impl Tiling {
    /// The tiling of a grid of `counts` grid bricks per axis.
    pub(crate) fn new(counts: [usize; 3]) -> Tiling {
        Tiling {
            counts,
            next_y: counts[1],
            next_z: 0,
            slab_end: 0,
        }
    }

    /// Takes the next part's box of grid bricks; whether it completes its z slab.
    pub(crate) fn accept(&mut self, bricks: &[Range<usize>; 3]) -> Result<bool> {
        let [bx, by, bz] = bricks.clone();
        if self.next_y == self.counts[1] {
            (self.next_y, self.next_z) = (0, self.slab_end);
        }
        let fits = bx == (0..self.counts[0])
            && by.start == self.next_y
            && bz.start == self.next_z
            && (self.next_y == 0 || bz.end == self.slab_end);
        if !fits {
            return Err(Error::parameter(format!(
                "the parts do not tile the grid: a part covers bricks y {by:?}, z {bz:?} where \
                 y from {}, z from {} was expected",
                self.next_y, self.next_z
            )));
        }
        (self.next_y, self.slab_end) = (by.end, bz.end);
        Ok(self.next_y == self.counts[1])
    }

    /// An error unless the parts taken cover the whole grid.
    pub(crate) fn finish(&self) -> Result<()> {
        if self.next_y == self.counts[1] && self.slab_end == self.counts[2] {
            return Ok(());
        }
        Err(Error::parameter(format!(
            "the parts do not tile the grid: they end at bricks y {}, z {} of {}, {}",
            self.next_y, self.slab_end, self.counts[1], self.counts[2]
        )))
    }
}
