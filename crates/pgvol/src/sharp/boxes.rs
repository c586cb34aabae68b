//! Small boxes of a grid around the cells near creases, so that the work of finding stored
//! vertices follows the creases rather than the grid.

use glam::Vec3;
use pgvol_core::Grid;

use super::cells::cell_at;

/// Edge of a box, in cells: large enough that the margin adds little, small enough that a
/// crease's box holds few cells far from it.
pub(crate) const BOX_CELLS: u64 = 16;

/// Cells of margin around a box's own cells. A cell's dual-contouring vertex depends only on
/// its own corners and edges, all in the sub-grid even without a margin (the padding that
/// closes a sub-grid's contour lies outside it); one layer more keeps the owned cells off the
/// sub-grid's faces for 1.4 times the nodes of a full box.
const MARGIN: u64 = 1;

/// A box of cells and the sub-grid to contour it on.
pub(crate) struct CellBox {
    /// The keys (on the whole grid) of the box's own cells, ascending.
    pub owned: Vec<u64>,
    /// Nodes of the whole grid around the owned cells and their margin: same spacing, origin
    /// on one of the whole grid's nodes.
    pub grid: Grid,
}

impl CellBox {
    /// The owned cells, named on the box's sub-grid of `grid`.
    pub(crate) fn owned_cells(&self, grid: &Grid) -> pgvol_contour::CellSet {
        // The sub-grid's first node, on `grid`.
        let first = ((self.grid.origin - grid.origin) / grid.spacing)
            .round()
            .to_array()
            .map(|x| x as u64);
        let mut set = pgvol_contour::CellSet::new(self.grid.dims);
        for &key in &self.owned {
            let c = cell_at(grid, key);
            let inside = set.insert([0, 1, 2].map(|a| (c[a] - first[a]) as usize));
            debug_assert!(inside, "an owned cell lies in its box's sub-grid");
        }
        set
    }
}

/// `keys` (ascending cells of `grid`) grouped by the box of [`BOX_CELLS`]³ cells each lies in,
/// each group with the sub-grid spanning its cells' bounds and the margin.
pub(crate) fn boxes(keys: &[u64], grid: &Grid) -> Vec<CellBox> {
    let mut by_box: Vec<([u64; 3], u64)> = keys
        .iter()
        .map(|&key| (cell_at(grid, key).map(|c| c / BOX_CELLS), key))
        .collect();
    by_box.sort_unstable_by_key(|&([x, y, z], key)| (z, y, x, key));
    let last_node = grid.dims.map(|n| n as u64 - 1);
    by_box
        .chunk_by(|a, b| a.0 == b.0)
        .map(|group| {
            let owned: Vec<u64> = group.iter().map(|g| g.1).collect();
            let mut lo = [u64::MAX; 3];
            let mut hi = [0u64; 3];
            for &key in &owned {
                let c = cell_at(grid, key);
                for a in 0..3 {
                    lo[a] = lo[a].min(c[a]);
                    hi[a] = hi[a].max(c[a]);
                }
            }
            // Nodes from the lowest cell's corner, less the margin, to the highest cell's far
            // corner, plus the margin.
            let first = lo.map(|x| x.saturating_sub(MARGIN));
            let end = [0, 1, 2].map(|a| (hi[a] + 1 + MARGIN).min(last_node[a]));
            let origin = grid.origin + Vec3::from(first.map(|x| x as f32)) * grid.spacing;
            let sub = Grid {
                origin,
                spacing: grid.spacing,
                dims: [0, 1, 2].map(|a| (end[a] - first[a] + 1) as usize),
                offset: grid.offset,
            };
            CellBox { owned, grid: sub }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sharp::cells::key_of;

    #[test]
    fn groups_cells_by_box_with_a_margin_inside_the_grid() {
        let grid = Grid {
            origin: Vec3::splat(-1.0),
            spacing: 0.125,
            dims: [41, 41, 41],
            offset: Default::default(),
        };
        let mut keys = vec![
            key_of(&grid, [0, 0, 0]),
            key_of(&grid, [3, 5, 2]),
            key_of(&grid, [17, 5, 2]),
            key_of(&grid, [39, 39, 39]),
        ];
        keys.sort_unstable();
        let boxes = boxes(&keys, &grid);
        assert_eq!(boxes.len(), 3);
        let first = &boxes[0];
        assert_eq!(first.owned.len(), 2);
        // Nodes of cells 0..=3, 0..=5, 0..=2 and one node of margin above, none below the grid.
        assert_eq!(first.grid.dims, [6, 8, 5]);
        assert_eq!(first.grid.origin, grid.origin);
        let second = &boxes[1];
        assert_eq!(second.grid.dims, [4, 4, 4]);
        assert_eq!(
            second.grid.origin,
            grid.origin + Vec3::new(16.0, 4.0, 1.0) * 0.125
        );
        // The last cell keeps its margin below and ends at the grid's last node.
        assert_eq!(boxes[2].grid.dims, [3, 3, 3]);
        assert_eq!(
            boxes[2].grid.origin,
            grid.origin + Vec3::splat(38.0 * 0.125)
        );
    }
}
