//! Triangles of one z slab of cells.

use glam::Vec3;

use crate::crossings::Layer;
use crate::cube::{edge_axis, face_corners, EDGE_START};
use crate::decider::joins_inside;
use crate::samples::Samples;
use crate::table::{case_table, CaseTable, CENTER};

/// Marks a triangle index as referring to the slab's `extra` vertices rather than an edge vertex;
/// the flag is resolved once all slabs are done and the extra vertices get their final place.
pub(crate) const EXTRA_FLAG: u32 = 1 << 31;

pub(crate) struct Slab {
    pub triangles: Vec<[u32; 3]>,
    /// Loop centre vertices (only for the rare loops that cannot be triangulated from their
    /// crossings alone).
    pub extra: Vec<Vec3>,
}

/// Vertices of the grid: per-layer crossings and where each layer's vertices start globally.
pub(crate) struct Vertices<'a> {
    pub layers: &'a [Layer],
    pub base: &'a [u32],
    pub positions: &'a [Vec3],
}

impl Vertices<'_> {
    /// Global index of the vertex on the edge along `axis` from node `n`.
    #[inline]
    pub fn find(&self, n: [usize; 3], axis: usize) -> u32 {
        let (keys, start) = self.layers[n[2]].row(n[1]);
        let key = (3 * n[0] + axis) as u32;
        let at = keys
            .binary_search(&key)
            .expect("a crossed cell edge always has a vertex");
        self.base[n[2]] + start + at as u32
    }
}

impl Vertices<'_> {
    /// Lower node and axis of the edge holding global vertex `g`.
    pub fn locate(&self, g: u32) -> ([usize; 3], usize) {
        let z = self.base.partition_point(|&b| b <= g) - 1;
        let (j, key) = self.layers[z].locate(g - self.base[z]);
        ([key as usize / 3, j, z], key as usize % 3)
    }
}

/// Triangles of the cells between node layers `k` and `k + 1`, in cell scan order.
pub(crate) fn slab_triangles(field: &Samples, verts: &Vertices, k: usize) -> Slab {
    let [nx, ny, _] = field.dims;
    let table = case_table();
    let mut slab = Slab {
        triangles: Vec::new(),
        extra: Vec::new(),
    };
    let mut candidates: Vec<usize> = Vec::new();
    for j in 0..ny - 1 {
        row_cells(verts, nx, j, k, &mut candidates);
        for &i in &candidates {
            cell_triangles(field, table, verts, [i, j, k], &mut slab);
        }
    }
    slab
}

fn cell_triangles(
    field: &Samples,
    table: &CaseTable,
    verts: &Vertices,
    cell: [usize; 3],
    slab: &mut Slab,
) {
    let [i, j, k] = cell;
    let Some((case, joined)) = cell_config(field, table, cell) else {
        return;
    };
    let crossed = table.crossed[case];
    let mut edge_vertex = [0u32; 12];
    let mut todo = crossed;
    while todo != 0 {
        let e = todo.trailing_zeros() as usize;
        todo &= todo - 1;
        let s = EDGE_START[e];
        edge_vertex[e] = verts.find([i + s[0], j + s[1], k + s[2]], edge_axis(e));
    }
    let entry = table.cell(case, joined);
    let first_extra = slab.extra.len() as u32;
    for &mask in entry.centers() {
        let (sum, n) = (0..12)
            .filter(|e| mask & (1 << e) != 0)
            .fold((Vec3::ZERO, 0.0), |(s, n), e| {
                (s + verts.positions[edge_vertex[e] as usize], n + 1.0)
            });
        slab.extra.push(sum / n);
    }
    let vertex = |code: u8| -> u32 {
        if code < CENTER {
            edge_vertex[code as usize]
        } else {
            EXTRA_FLAG | (first_extra + u32::from(code - CENTER))
        }
    };
    slab.triangles
        .extend(entry.triangles().iter().map(|t| t.map(vertex)));
}

/// The cells of row `j` in slab `k` that have a crossed edge, ascending, into `out`.
pub(crate) fn row_cells(verts: &Vertices, nx: usize, j: usize, k: usize, out: &mut Vec<usize>) {
    // Every edge of a cell in this row is listed in rows j and j + 1 of layers k and k + 1,
    // with its lower node at x = i or i + 1; cells next to no crossing are never visited.
    out.clear();
    for (layer, row) in [(k, j), (k, j + 1), (k + 1, j), (k + 1, j + 1)] {
        for &key in verts.layers[layer].row(row).0 {
            let x = key as usize / 3;
            out.extend((x.saturating_sub(1)..=x).filter(|&i| i + 1 < nx));
        }
    }
    out.sort_unstable();
    out.dedup();
}

/// The inside-corner case of `cell` and the asymptotic decider's choice on each ambiguous face,
/// or `None` when no edge of the cell is crossed.
#[inline]
pub(crate) fn cell_config(
    field: &Samples,
    table: &CaseTable,
    cell: [usize; 3],
) -> Option<(usize, u8)> {
    let [i, j, k] = cell;
    let mut values = [0f32; 8];
    let mut case = 0usize;
    for (c, v) in values.iter_mut().enumerate() {
        *v = field.values[field.index(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))];
        case |= usize::from(field.inside(*v)) << c;
    }
    if table.crossed[case] == 0 {
        return None;
    }
    let mut joined = 0u8;
    let mut ambiguous = table.ambiguous[case];
    while ambiguous != 0 {
        let f = ambiguous.trailing_zeros() as usize;
        ambiguous &= ambiguous - 1;
        let corners = face_corners(f);
        let g = corners.map(|c| values[c] - field.iso);
        if joins_inside(g, (case >> corners[0]) & 1 == 1) {
            joined |= 1 << f;
        }
    }
    Some((case, joined))
}
