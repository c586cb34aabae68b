//! The crossed cells of a block and their configurations.

use crate::blocks::{box_index, BoxValues};
use crate::crossings::BlockBox;
use crate::cube::face_corners;
use crate::decider::joins_inside;
use crate::table::CaseTable;

/// Calls `visit(cell, case, joined)` for every cell owned by `block` that has a crossed edge,
/// in scan order (x fastest): `case` is the bit set of inside corners and `joined` the faces on
/// which the asymptotic decider connects the inside corners.
///
/// A row of cells is classified with a few bit operations on the box's row masks, and only
/// crossed cells are looked at further.
pub(crate) fn for_crossed_cells(
    table: &CaseTable,
    iso: f32,
    block: BlockBox,
    mut visit: impl FnMut([usize; 3], usize, u8),
) {
    let BlockBox {
        origin: o,
        values,
        masks,
    } = block;
    // Cells owned by the block along each axis: those with their upper nodes in the box.
    let cells = masks.nodes.map(|n| n - 1);
    if cells.contains(&0) {
        return;
    }
    let rows = &masks.rows;
    let cell_mask = (1u16 << cells[0]) - 1;
    for dk in 0..cells[2] {
        for dj in 0..cells[1] {
            let m = [
                rows[dk][dj],
                rows[dk][dj + 1],
                rows[dk + 1][dj],
                rows[dk + 1][dj + 1],
            ];
            let all = m[0] & m[1] & m[2] & m[3];
            let any = m[0] | m[1] | m[2] | m[3];
            let uniform = (all & (all >> 1)) | !(any | (any >> 1));
            let mut crossed = !uniform & cell_mask;
            while crossed != 0 {
                let di = crossed.trailing_zeros() as usize;
                crossed &= crossed - 1;
                let case = m.iter().enumerate().fold(0usize, |c, (q, &r)| {
                    c | (usize::from((r >> di) & 3) << (2 * q))
                });
                let cell = [o[0] + di, o[1] + dj, o[2] + dk];
                let joined = decide_faces(values, iso, table, [di, dj, dk], case);
                visit(cell, case, joined);
            }
        }
    }
}

/// The asymptotic decider's choice on each ambiguous face of the cell at `d` in box `values`
/// (bit set of faces whose inside corners connect).
#[inline]
fn decide_faces(values: &BoxValues, iso: f32, table: &CaseTable, d: [usize; 3], case: usize) -> u8 {
    let mut ambiguous = table.ambiguous[case];
    if ambiguous == 0 {
        return 0;
    }
    let [i, j, k] = d;
    let values: [f32; 8] =
        std::array::from_fn(|c| values[box_index([i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)])]);
    let mut joined = 0u8;
    while ambiguous != 0 {
        let f = ambiguous.trailing_zeros() as usize;
        ambiguous &= ambiguous - 1;
        let corners = face_corners(f);
        let g = corners.map(|c| values[c] - iso);
        if joins_inside(g, (case >> corners[0]) & 1 == 1) {
            joined |= 1 << f;
        }
    }
    joined
}
