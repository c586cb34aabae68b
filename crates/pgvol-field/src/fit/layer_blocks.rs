//! Sample rows grouped by the blocks of z-layers their stencils reach. A transposed product gives
//! each block to one task, which adds the terms of every row reaching the block in row order:
//! each coefficient's sum then has one order whatever the number of threads, and no two tasks
//! write to the same coefficient, so no partial sums need merging.

use std::ops::{Range, RangeInclusive};

/// Z-layers per block: a few stencil widths, so that rows reaching two blocks are a minority,
/// and enough blocks at 64³ to keep two threads busy.
pub(crate) const LAYERS: usize = 8;

pub(crate) struct LayerBlocks {
    /// Layers per block (the last one may have fewer).
    pub layers: usize,
    /// Per block, the rows that may reach it: every row that does, and a few that do not when
    /// rows are not sorted by layer.
    pub rows: Vec<Range<usize>>,
}

impl LayerBlocks {
    /// Blocks of `layers` z-layers out of `nz`, for rows reaching the layers `reach(i)`.
    pub fn new(
        nz: usize,
        layers: usize,
        rows: usize,
        reach: impl Fn(usize) -> RangeInclusive<usize>,
    ) -> LayerBlocks {
        let layers = layers.max(1);
        let blocks = nz.div_ceil(layers);
        // The highest layer reached up to row i and the lowest from row i on are monotone in i:
        // a block's rows start where the first passes its first layer and stop where the second
        // passes its end, found in one sweep each way.
        let mut starts = vec![rows; blocks];
        let mut next = 0;
        let mut top = 0;
        for i in 0..rows {
            top = top.max(*reach(i).end());
            while next < blocks && top >= next * layers {
                starts[next] = i;
                next += 1;
            }
        }
        let mut stops = vec![0; blocks];
        let mut next = blocks;
        let mut bottom = usize::MAX;
        for i in (0..rows).rev() {
            bottom = bottom.min(*reach(i).start());
            while next > 0 && bottom < ((next - 1) * layers + layers).min(nz) {
                stops[next - 1] = i + 1;
                next -= 1;
            }
        }
        let rows = starts
            .into_iter()
            .zip(stops)
            .map(|(start, stop)| start..stop.max(start))
            .collect();
        LayerBlocks { layers, rows }
    }

    /// The layers of block `b`, out of `nz`.
    pub fn layer_range(&self, b: usize, nz: usize) -> Range<usize> {
        b * self.layers..((b + 1) * self.layers).min(nz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every row reaching a block is among the block's rows, whatever the order of the rows.
    #[test]
    fn blocks_hold_every_row_that_reaches_them() {
        let nz = 37;
        for shuffle in [1usize, 7, 23] {
            let reach = |i: usize| {
                let lo = (i * shuffle) % 34;
                lo..=(lo + 3).min(nz - 1)
            };
            let rows = 120;
            let blocks = LayerBlocks::new(nz, 5, rows, reach);
            assert_eq!(blocks.rows.len(), 8);
            for (b, range) in blocks.rows.iter().enumerate() {
                let layers = blocks.layer_range(b, nz);
                for i in 0..rows {
                    let r = reach(i);
                    if *r.start() < layers.end && *r.end() >= layers.start {
                        assert!(range.contains(&i), "row {i} block {b} {range:?}");
                    }
                }
            }
        }
        // Sorted rows give tight ranges.
        let blocks = LayerBlocks::new(20, 4, 20, |i| i..=i);
        assert_eq!(blocks.rows, vec![0..4, 4..8, 8..12, 12..16, 16..20]);
    }
}
