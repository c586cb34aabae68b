//! Surface components of a cell for dual contouring: the loops that the face-traced contour
//! forms in each cell configuration (the same loops marching cubes triangulates), one dual vertex
//! each, as in Manifold Dual Contouring (Schaefer, Ju and Warren 2007).

use std::sync::OnceLock;

use crate::cube::{face_edges, EDGE_START};
use crate::table::{case_table, loops};

/// No loop: the edge is not crossed.
pub(crate) const NONE: u8 = u8::MAX;

/// Loop membership of one cell configuration.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Components {
    /// Loop index of each crossed cube edge, [`NONE`] elsewhere.
    pub edge_loop: [u8; 12],
    pub n_loops: u8,
    /// Per loop, the faces (bit set) whose four crossings all belong to it: such a loop crosses
    /// the face twice, and when the cell across does the same, the two dual vertices are joined
    /// by two distinct dual edges, which a triangle mesh has to split apart.
    pub double_faces: [u8; 4],
}

/// Components of every case and decider choice, laid out like the marching cubes table.
pub(crate) fn components(case: usize, joined: u8) -> &'static Components {
    static TABLE: OnceLock<Vec<Components>> = OnceLock::new();
    let table = TABLE.get_or_init(build);
    &table[case * 64 + (joined & case_table().ambiguous[case]) as usize]
}

fn build() -> Vec<Components> {
    let mut out = Vec::with_capacity(256 * 64);
    for case in 0..256 {
        for joined in 0..64u8 {
            let mut c = Components {
                edge_loop: [NONE; 12],
                n_loops: 0,
                double_faces: [0; 4],
            };
            for (l, lp) in loops(case, joined).iter().enumerate() {
                for &e in lp {
                    c.edge_loop[e] = l as u8;
                }
                c.n_loops += 1;
            }
            for f in 0..6 {
                let ids = face_edges(f).map(|e| c.edge_loop[e]);
                if ids[0] != NONE && ids.iter().all(|&l| l == ids[0]) {
                    c.double_faces[ids[0] as usize] |= 1 << f;
                }
            }
            out.push(c);
        }
    }
    out
}

/// Position of a cell around its crossed edge `e`, counter-clockwise about the edge axis:
/// 0 at the cell below on both plane axes, then 1 (above on the first), 2, 3.
#[inline]
pub(crate) fn ring_slot(e: usize) -> usize {
    let axis = e / 4;
    let (u, v) = crate::cube::plane_axes(axis);
    let o = EDGE_START[e];
    // The cell lies on the low side of the edge along u when the edge sits at its high u face.
    let (du, dv) = (1 - o[u], 1 - o[v]);
    [[0, 3], [1, 2]][du][dv]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loops_never_exceed_four_and_doubles_are_rare() {
        let mut doubles = 0;
        for case in 0..256 {
            for joined in 0..64u8 {
                let c = components(case, joined);
                assert!(c.n_loops <= 4);
                for l in 0..c.n_loops as usize {
                    doubles += usize::from(c.double_faces[l] != 0);
                }
                for l in c.n_loops as usize..4 {
                    assert_eq!(c.double_faces[l], 0);
                }
            }
        }
        assert!(
            doubles > 0,
            "a loop around a tunnel must cross a face twice"
        );
    }

    #[test]
    fn ring_slots_of_a_cells_edges_along_one_axis_are_distinct() {
        for axis in 0..3 {
            let mut seen = [false; 4];
            for e in 4 * axis..4 * axis + 4 {
                seen[ring_slot(e)] = true;
            }
            assert!(seen.iter().all(|&s| s));
        }
    }
}
