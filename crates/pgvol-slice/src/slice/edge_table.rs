//! The vertex on each crossed edge of a layer, found by the edge's id.
//!
//! A layer's crossings are made block by block and looked up four per mixed cell while the
//! segments are linked. An open-addressing table finds one in a probe or two; sorting the
//! crossings by id and searching them took a tenth of a fandisk slice at 1024³.

/// Edge ids to vertex indices, for ids below `usize::MAX`.
pub(crate) struct EdgeTable {
    /// `(id, vertex)` slots, `usize::MAX` where empty; the length is a power of two.
    slots: Vec<(usize, u32)>,
}

const EMPTY: usize = usize::MAX;

impl EdgeTable {
    /// A table for the edges `ids` (distinct), vertex `k` on `ids[k]`.
    pub(crate) fn new(ids: impl ExactSizeIterator<Item = usize>) -> EdgeTable {
        // At most half full: probes stay short.
        let len = (2 * ids.len()).next_power_of_two().max(16);
        let mut table = EdgeTable {
            slots: vec![(EMPTY, u32::MAX); len],
        };
        for (vertex, id) in ids.enumerate() {
            debug_assert_ne!(id, EMPTY);
            let mut at = table.home(id);
            while table.slots[at].0 != EMPTY {
                at = (at + 1) & (len - 1);
            }
            table.slots[at] = (id, vertex as u32);
        }
        table
    }

    /// The vertex on edge `id`, `u32::MAX` when the edge holds none.
    #[inline]
    pub(crate) fn vertex(&self, id: usize) -> u32 {
        let mask = self.slots.len() - 1;
        let mut at = self.home(id);
        loop {
            let (key, vertex) = self.slots[at];
            if key == id {
                return vertex;
            }
            if key == EMPTY {
                return u32::MAX;
            }
            at = (at + 1) & mask;
        }
    }

    #[inline]
    fn home(&self, id: usize) -> usize {
        // Fibonacci hashing: neighbouring ids land far apart.
        let h = (id as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        (h >> (64 - self.slots.len().trailing_zeros())) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_edge_finds_its_vertex_and_others_none() {
        // Ids in runs and strides, as a layer's crossings come.
        let ids: Vec<usize> = (0..3000)
            .map(|k| 2 * (k % 97) + 4096 * (k / 97) + (k & 1))
            .collect();
        let mut distinct = ids.clone();
        distinct.sort_unstable();
        distinct.dedup();
        let table = EdgeTable::new(distinct.iter().copied());
        for (k, &id) in distinct.iter().enumerate() {
            assert_eq!(table.vertex(id), k as u32);
        }
        for id in [1usize << 40, 5, 4095 * 4096 + 3] {
            if !distinct.contains(&id) {
                assert_eq!(table.vertex(id), u32::MAX);
            }
        }
        assert_eq!(EdgeTable::new(std::iter::empty()).vertex(3), u32::MAX);
    }
}
