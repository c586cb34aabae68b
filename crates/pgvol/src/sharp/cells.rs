//! Which cell of a grid each vertex of a dual mesh belongs to.
//!
//! A mesh contoured with its vertices' cells (`pgvol_contour::DualMesh::homes`) says so.
//! Otherwise dual contouring kept every cell's vertex `CELL_MARGIN` (1e-3 of a cell) clear of
//! the cell's faces, and the only other vertices of its meshes (midpoints of doubled dual
//! edges) lie on faces or edges; so a vertex strictly inside a cell, by half that margin, is
//! that cell's vertex.

use glam::Vec3;
use pgvol_core::{Grid, Mesh};

/// Half the margin dual contouring keeps between a cell's vertex and the cell's faces, in cells.
const INSIDE: f32 = 0.5e-3;

/// A cell vertex: the cell's key `i + (nx − 1)(j + (ny − 1) k)`, the vertex's index and its
/// position in the cell, in cell units.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CellVertex {
    pub key: u64,
    pub vertex: u32,
    pub local: Vec3,
}

/// The cell `p` (local coordinates) lies strictly inside on `grid`, with its position there in
/// cell units; `None` near a face or outside the grid.
pub(crate) fn cell_of(grid: &Grid, p: Vec3) -> Option<(u64, Vec3)> {
    let u = (p - grid.origin) / grid.spacing;
    let c = u.floor();
    let f = u - c;
    if !(f.cmpge(Vec3::splat(INSIDE)).all() && f.cmple(Vec3::splat(1.0 - INSIDE)).all()) {
        return None;
    }
    let [nx, ny, nz] = grid.dims.map(|n| n as i64 - 1);
    let [i, j, k] = c.to_array().map(|x| x as i64);
    if i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz {
        return None;
    }
    Some(((i + nx * (j + ny * k)) as u64, f))
}

/// The cell vertices of `mesh` on `grid`: the first `homes.len()` vertices lie in the cells
/// whose lowest corners `homes` gives (possibly outside them); without `homes`, each vertex
/// strictly inside a cell is its vertex.
fn cell_vertices<'a>(
    mesh: &'a Mesh,
    homes: &'a [Vec3],
    grid: &'a Grid,
) -> impl Iterator<Item = CellVertex> + 'a {
    let h = grid.spacing;
    let homed = homes.iter().zip(&mesh.positions).enumerate();
    let homed = homed.filter_map(move |(v, (&corner, &p))| {
        let (key, _) = cell_of(grid, corner + Vec3::splat(0.5 * h))?;
        Some(CellVertex {
            key,
            vertex: v as u32,
            local: (p - corner) / h,
        })
    });
    let placed = mesh
        .positions
        .iter()
        .enumerate()
        .filter(|_| homes.is_empty());
    let placed = placed.filter_map(move |(v, &p)| {
        cell_of(grid, p).map(|(key, local)| CellVertex {
            key,
            vertex: v as u32,
            local,
        })
    });
    homed.chain(placed)
}

/// The vertices of `mesh` (with `homes` as [`cell_vertices`] takes them) that are alone in
/// their cell of `grid`, by ascending key. Cells with two or more vertices (two sheets through
/// one cell) are left out: their vertices are not interchangeable between two contourings.
pub(crate) fn single_vertices(mesh: &Mesh, homes: &[Vec3], grid: &Grid) -> Vec<CellVertex> {
    let mut all: Vec<CellVertex> = cell_vertices(mesh, homes, grid).collect();
    all.sort_unstable_by_key(|c| (c.key, c.vertex));
    let mut single = Vec::with_capacity(all.len());
    let mut i = 0;
    while i < all.len() {
        let mut end = i + 1;
        while end < all.len() && all[end].key == all[i].key {
            end += 1;
        }
        if end == i + 1 {
            single.push(all[i]);
        }
        i = end;
    }
    single
}

/// The keys of the cells of `grid` holding a vertex of `mesh` (with `homes` as
/// [`cell_vertices`] takes them), ascending.
pub(crate) fn cell_keys(mesh: &Mesh, homes: &[Vec3], grid: &Grid) -> Vec<u64> {
    let mut keys: Vec<u64> = cell_vertices(mesh, homes, grid).map(|c| c.key).collect();
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// The key of the cell `(i, j, k)` on `grid`.
pub(crate) fn key_of(grid: &Grid, [i, j, k]: [u64; 3]) -> u64 {
    let [nx, ny, _] = grid.dims.map(|n| n as u64 - 1);
    i + nx * (j + ny * k)
}

/// The cell `(i, j, k)` of a key on `grid`.
pub(crate) fn cell_at(grid: &Grid, key: u64) -> [u64; 3] {
    let [nx, ny, _] = grid.dims.map(|n| n as u64 - 1);
    [key % nx, (key / nx) % ny, key / (nx * ny)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_cell_and_skips_faces_and_shared_cells() {
        let grid = Grid {
            origin: Vec3::splat(-1.0),
            spacing: 0.5,
            dims: [5, 5, 5],
            offset: Default::default(),
        };
        let (key, local) = cell_of(&grid, Vec3::new(-0.9, 0.2, 0.6)).unwrap();
        assert_eq!(cell_at(&grid, key), [0, 2, 3]);
        assert_eq!(key_of(&grid, [0, 2, 3]), key);
        assert!((local - Vec3::new(0.2, 0.4, 0.2)).abs().max_element() < 1e-5);
        assert!(cell_of(&grid, Vec3::new(-0.5, 0.2, 0.6)).is_none());
        assert!(cell_of(&grid, Vec3::new(1.2, 0.2, 0.6)).is_none());
        let mesh = Mesh::new(
            vec![
                Vec3::new(-0.9, 0.2, 0.6),
                Vec3::new(-0.8, 0.3, 0.7),
                Vec3::new(0.1, 0.1, 0.1),
            ],
            vec![[0, 1, 2]],
        );
        let single = single_vertices(&mesh, &[], &grid);
        assert_eq!(single.len(), 1);
        assert_eq!(single[0].vertex, 2);
        // With their cells given, vertices may lie outside them: the first two are the cells
        // at (0, 2, 3) and (1, 2, 3), the third (on no cell list) is left out.
        let homes = [Vec3::new(-1.0, 0.0, 0.5), Vec3::new(-0.5, 0.0, 0.5)];
        let homed = single_vertices(&mesh, &homes, &grid);
        assert_eq!(homed.len(), 2);
        assert_eq!(cell_at(&grid, homed[1].key), [1, 2, 3]);
        assert!(
            (homed[1].local - Vec3::new(-0.6, 0.6, 0.4))
                .abs()
                .max_element()
                < 1e-5
        );
    }
}
