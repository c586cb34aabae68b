//! Marching cubes triangles of one block of cells.

use glam::Vec3;

use crate::cells::for_crossed_cells;
use crate::crossings::Crossings;
use crate::cube::{edge_axis, EDGE_START};
use crate::table::{case_table, CaseTable, CENTER};

/// Marks a triangle index as referring to the part's `extra` vertices rather than an edge vertex;
/// the flag is resolved once all parts are done and the extra vertices get their final place.
pub(crate) const EXTRA_FLAG: u32 = 1 << 31;

#[derive(Default)]
pub(crate) struct Part {
    pub triangles: Vec<[u32; 3]>,
    /// Loop centre vertices (only for the rare loops that cannot be triangulated from their
    /// crossings alone).
    pub extra: Vec<Vec3>,
    /// The extra vertices' unit normals, when the crossings have normals: their loop's
    /// normals averaged.
    pub extra_normals: Vec<Vec3>,
}

/// Triangles of the cells owned by the active block at `slot`, in cell scan order.
pub(crate) fn block_triangles(crossings: &Crossings, iso: f32, slot: usize) -> Part {
    let table = case_table();
    // About two triangles per vertex on a closed surface.
    let mut part = Part {
        triangles: Vec::with_capacity(2 * crossings.block_len(slot) + 8),
        ..Part::default()
    };
    let block = crossings.block(slot);
    let origin = block.origin;
    for_crossed_cells(table, iso, block, |cell, case, joined| {
        cell_triangles(
            table,
            crossings,
            (slot, origin),
            cell,
            case,
            joined,
            &mut part,
        );
    });
    part
}

fn cell_triangles(
    table: &CaseTable,
    verts: &Crossings,
    home: (usize, [usize; 3]),
    cell: [usize; 3],
    case: usize,
    joined: u8,
    part: &mut Part,
) {
    let [i, j, k] = cell;
    let crossed = table.crossed[case];
    let mut edge_vertex = [0u32; 12];
    let mut todo = crossed;
    while todo != 0 {
        let e = todo.trailing_zeros() as usize;
        todo &= todo - 1;
        let s = EDGE_START[e];
        edge_vertex[e] =
            verts.find_from(home.0, home.1, [i + s[0], j + s[1], k + s[2]], edge_axis(e));
    }
    let entry = table.cell(case, joined);
    let first_extra = part.extra.len() as u32;
    let with_normals = !verts.normals.is_empty();
    for &mask in entry.centers() {
        let loop_vertices = (0..12)
            .filter(|e| mask & (1 << e) != 0)
            .map(|e| edge_vertex[e] as usize);
        let (sum, n) = loop_vertices.clone().fold((Vec3::ZERO, 0.0), |(s, n), v| {
            (s + verts.positions[v], n + 1.0)
        });
        part.extra.push(sum / n);
        if with_normals {
            let normal: Vec3 = loop_vertices.map(|v| verts.normals[v]).sum();
            part.extra_normals.push(normal.normalize_or_zero());
        }
    }
    let vertex = |code: u8| -> u32 {
        if code < CENTER {
            edge_vertex[code as usize]
        } else {
            EXTRA_FLAG | (first_extra + u32::from(code - CENTER))
        }
    };
    part.triangles
        .extend(entry.triangles().iter().map(|t| t.map(vertex)));
}
