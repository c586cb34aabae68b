//! Decoding: the stored vertices replace the smooth field's in their cells.

use glam::Vec3;
use pgvol_core::Grid;
use pgvol_format::sharp::SharpCells;

use super::cells::cell_of;

/// The stored vertex, in cell units, of the cell of `grid` whose lowest corner is `corner`;
/// `None` for a cell `cells` does not store. Dual contouring asks this of every cell the decoded
/// field crosses once, so cells it does not cross, or crosses twice, keep their own vertex.
pub(crate) fn stored_vertex(grid: &Grid, cells: &SharpCells, corner: Vec3) -> Option<Vec3> {
    let (key, _) = cell_of(grid, corner + Vec3::splat(0.5 * grid.spacing))?;
    let i = cells.keys.binary_search(&key).ok()?;
    Some(Vec3::from(cells.position(i)))
}
