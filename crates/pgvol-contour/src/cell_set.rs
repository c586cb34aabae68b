//! A set of a grid's cells, for callers that need the dual-contouring vertices of a few cells
//! only (an encoder comparing two contours near creases): the other cells' crossings, planes
//! and quads are skipped, and a cell's vertex depends only on its own corners and edges, so the
//! cells asked for get the vertices a whole contouring gives them.

/// Cells of a grid, each named by its lowest node `[i, j, k]`: a flag per cell of the grid,
/// meant for the small sub-grids that hold the cells of interest.
#[derive(Clone, Debug)]
pub struct CellSet {
    /// Cells per axis.
    cells: [usize; 3],
    members: Vec<bool>,
}

impl CellSet {
    /// No cell of a grid of `dims` nodes per axis.
    pub fn new(dims: [usize; 3]) -> Self {
        let cells = dims.map(|n| n.saturating_sub(1));
        CellSet {
            cells,
            members: vec![false; cells.iter().product()],
        }
    }

    /// Adds `cell`; a cell outside the grid is not added, and `false` says so.
    pub fn insert(&mut self, cell: [usize; 3]) -> bool {
        match self.index(cell) {
            Some(i) => {
                self.members[i] = true;
                true
            }
            None => false,
        }
    }

    /// Whether `cell` is in the set.
    pub fn contains(&self, cell: [usize; 3]) -> bool {
        self.index(cell).is_some_and(|i| self.members[i])
    }

    /// Whether the set holds the cell of a grid padded by `pad` nodes on every side whose lowest
    /// node is `padded` there.
    pub(crate) fn contains_padded(&self, padded: [usize; 3], pad: usize) -> bool {
        padded.iter().all(|&x| x >= pad) && self.contains(padded.map(|x| x - pad))
    }

    fn index(&self, [i, j, k]: [usize; 3]) -> Option<usize> {
        let [nx, ny, nz] = self.cells;
        (i < nx && j < ny && k < nz).then(|| i + nx * (j + ny * k))
    }
}

/// Whether any of the four cells around the grid edge from node `n` along `axis` is one that
/// `keep` names.
pub(crate) fn edge_touches(keep: impl Fn([usize; 3]) -> bool, n: [usize; 3], axis: usize) -> bool {
    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
    (0..4).any(|q| {
        let (db, dc) = (q & 1, q >> 1);
        if n[b] < db || n[c] < dc {
            return false;
        }
        let mut cell = n;
        cell[b] -= db;
        cell[c] -= dc;
        keep(cell)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holds_the_cells_inserted_and_finds_the_edges_around_them() {
        let mut set = CellSet::new([4, 5, 6]);
        assert!(set.insert([1, 2, 3]));
        assert!(!set.insert([3, 0, 0]), "x has 3 cells");
        assert!(set.contains([1, 2, 3]));
        assert!(!set.contains([2, 2, 3]));
        assert!(set.contains_padded([2, 3, 4], 1));
        assert!(!set.contains_padded([0, 3, 4], 1));
        let keep = |c| set.contains(c);
        // The cell's twelve edges, and no edge of a cell beside it alone.
        for (n, axis) in [
            ([1, 2, 3], 0),
            ([1, 3, 4], 0),
            ([1, 3, 3], 2),
            ([2, 2, 3], 1),
        ] {
            assert!(edge_touches(keep, n, axis), "{n:?} {axis}");
        }
        assert!(!edge_touches(keep, [3, 2, 3], 1));
        assert!(!edge_touches(keep, [1, 4, 3], 0));
        assert!(!edge_touches(keep, [0, 0, 0], 2));
    }
}
