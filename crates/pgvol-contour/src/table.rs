//! Case table derived by tracing the contour around the cube faces.
//!
//! A case is the bit set of inside corners; for each case and each choice of which ambiguous faces
//! join their inside corners, the table lists the cell's triangles as cube-edge indices. Deriving
//! it (rather than transcribing a classic table) makes every face's segments a function of that
//! face alone, which is what lets neighbouring cells stitch together exactly.

use std::sync::OnceLock;

use glam::Vec3;

use crate::cube::{edge_axis, edge_start, face_corners, face_edges, share_face};
use crate::triangulate::triangulate_loop;

/// Most triangles a cell can produce: 12 crossings, one triangle each when loops need centres.
pub(crate) const MAX_TRIS: usize = 12;
/// Triangle corner codes from `CENTER` up name an added vertex at the centre of loop
/// `code - CENTER`; lower codes are cube edges.
pub(crate) const CENTER: u8 = 12;

/// Triangles of one cell configuration.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct CellTriangles {
    pub tris: [[u8; 3]; MAX_TRIS],
    pub len: u8,
    /// Crossed edges (bit set) of each loop that needs a centre vertex, because every
    /// triangulation of it would use a chord lying on a cube face.
    pub centers: [u16; 4],
    pub n_centers: u8,
}

impl CellTriangles {
    pub fn triangles(&self) -> &[[u8; 3]] {
        &self.tris[..self.len as usize]
    }

    pub fn centers(&self) -> &[u16] {
        &self.centers[..self.n_centers as usize]
    }
}

pub(crate) struct CaseTable {
    /// Cube edges (bit set) whose end corners differ, per case.
    pub crossed: [u16; 256],
    /// Faces (bit set) with four crossings, per case.
    pub ambiguous: [u8; 256],
    cells: Vec<CellTriangles>,
}

impl CaseTable {
    /// Triangles for `case` when the faces in `joined` connect their inside corners.
    #[inline]
    pub fn cell(&self, case: usize, joined: u8) -> &CellTriangles {
        &self.cells[case * 64 + joined as usize]
    }
}

pub(crate) fn case_table() -> &'static CaseTable {
    static TABLE: OnceLock<CaseTable> = OnceLock::new();
    TABLE.get_or_init(build)
}

fn inside(case: usize, corner: usize) -> bool {
    (case >> corner) & 1 == 1
}

/// Faces with four crossings: diagonal corners equal, adjacent corners different.
fn ambiguous_faces(case: usize) -> u8 {
    (0..6)
        .filter(|&f| {
            let c = face_corners(f).map(|c| inside(case, c));
            c[0] == c[2] && c[1] == c[3] && c[0] != c[1]
        })
        .fold(0, |m, f| m | (1 << f))
}

/// Successor of each crossed edge along the contour. On every face a segment runs from the
/// crossing where the counter-clockwise walk enters the inside to the one where it leaves; on
/// ambiguous faces "separate" pairs each entering crossing with the next crossing and "join" with
/// the previous one. The neighbour sees the face wound the other way, so it derives the same
/// segments reversed.
pub(crate) fn successors(case: usize, joined: u8) -> [Option<usize>; 12] {
    let mut next = [None; 12];
    for f in 0..6 {
        let corners = face_corners(f);
        let edges = face_edges(f);
        let ins = corners.map(|c| inside(case, c));
        let entering = |i: usize| !ins[i] && ins[(i + 1) % 4];
        let crossed = |i: usize| ins[i] != ins[(i + 1) % 4];
        let count = (0..4).filter(|&i| crossed(i)).count();
        for i in (0..4).filter(|&i| entering(i)) {
            let j = match count {
                2 => (1..4).map(|d| (i + d) % 4).find(|&j| crossed(j)).unwrap(),
                4 if joined & (1 << f) != 0 => (i + 3) % 4,
                4 => (i + 1) % 4,
                _ => unreachable!("a square has an even number of sign changes"),
            };
            debug_assert!(next[edges[i]].is_none());
            next[edges[i]] = Some(edges[j]);
        }
    }
    next
}

/// Closed loops of crossed edges, each starting at its lowest edge.
pub(crate) fn loops(case: usize, joined: u8) -> Vec<Vec<usize>> {
    let next = successors(case, joined);
    let mut seen = [false; 12];
    let mut out = Vec::new();
    for start in 0..12 {
        if next[start].is_none() || seen[start] {
            continue;
        }
        let mut lp = Vec::new();
        let mut e = start;
        while !seen[e] {
            seen[e] = true;
            lp.push(e);
            e = next[e].expect("every crossing continues on its other face");
        }
        assert_eq!(e, start, "contour segments must close into loops");
        out.push(lp);
    }
    out
}

fn edge_midpoint(e: usize) -> Vec3 {
    let mut p = Vec3::from_array(edge_start(e).map(|x| x as f32));
    p[edge_axis(e)] = 0.5;
    p
}

fn cell_triangles(case: usize, joined: u8) -> CellTriangles {
    let mut cell = CellTriangles::default();
    let push = |cell: &mut CellTriangles, t: [u8; 3]| {
        cell.tris[cell.len as usize] = t;
        cell.len += 1;
    };
    for lp in loops(case, joined) {
        let points: Vec<Vec3> = lp.iter().map(|&e| edge_midpoint(e)).collect();
        // A chord between crossings on one face could also be chosen by the neighbour across that
        // face, giving an edge with four triangles; chords through the cell interior are private.
        match triangulate_loop(&points, |i, j| !share_face(lp[i], lp[j])) {
            Some(tris) => {
                for t in tris {
                    push(&mut cell, t.map(|i| lp[i] as u8));
                }
            }
            None => {
                let c = CENTER + cell.n_centers;
                cell.centers[cell.n_centers as usize] = lp.iter().fold(0, |m, &e| m | (1 << e));
                cell.n_centers += 1;
                for i in 0..lp.len() {
                    push(&mut cell, [c, lp[i] as u8, lp[(i + 1) % lp.len()] as u8]);
                }
            }
        }
    }
    cell
}

fn build() -> CaseTable {
    let mut crossed = [0u16; 256];
    let mut ambiguous = [0u8; 256];
    let mut cells = vec![CellTriangles::default(); 256 * 64];
    for case in 0..256 {
        crossed[case] = (0..12)
            .filter(|&e| {
                let s = edge_start(e);
                let a = s[0] | (s[1] << 1) | (s[2] << 2);
                inside(case, a) != inside(case, a | (1 << edge_axis(e)))
            })
            .fold(0, |m, e| m | (1 << e));
        ambiguous[case] = ambiguous_faces(case);
        for joined in 0..64u8 {
            let used = joined & ambiguous[case];
            cells[case * 64 + joined as usize] = if used == joined {
                cell_triangles(case, joined)
            } else {
                // Decisions on faces that are not ambiguous have no effect.
                cells[case * 64 + used as usize]
            };
        }
    }
    CaseTable {
        crossed,
        ambiguous,
        cells,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_crossing_is_in_exactly_one_loop() {
        let table = case_table();
        for case in 0..256 {
            for joined in 0..64u8 {
                let mut mask = 0u16;
                for lp in loops(case, joined) {
                    assert!(lp.len() >= 3);
                    for e in lp {
                        assert_eq!(mask & (1 << e), 0);
                        mask |= 1 << e;
                    }
                }
                assert_eq!(mask, table.crossed[case], "case {case}");
            }
        }
    }

    #[test]
    fn complementary_cases_give_reversed_loops() {
        // Swapping inside and outside turns "join" into "separate" and reverses every segment.
        for case in 0..256 {
            let amb = ambiguous_faces(case);
            for joined in 0..64u8 {
                let joined = joined & amb;
                let a = successors(case, joined);
                let b = successors(255 - case, amb & !joined);
                for (e, next) in a.iter().enumerate() {
                    if let Some(n) = *next {
                        assert_eq!(b[n], Some(e), "case {case} joined {joined:06b}");
                    }
                }
            }
        }
    }

    #[test]
    fn triangle_counts_match_loop_sizes() {
        let table = case_table();
        let mut with_centers = 0;
        for case in 0..256 {
            for joined in 0..64u8 {
                let cell = table.cell(case, joined);
                let lps = loops(case, joined & table.ambiguous[case]);
                let points: usize = lps.iter().map(Vec::len).sum();
                let expect = points - 2 * lps.len() + 2 * cell.centers().len();
                assert_eq!(cell.triangles().len(), expect);
                with_centers += usize::from(!cell.centers().is_empty());
            }
        }
        println!("table entries needing a centre vertex: {with_centers}");
    }
}
