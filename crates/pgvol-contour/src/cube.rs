//! Numbering of the corners, edges and faces of one grid cell.
//!
//! Corner `c` sits at offset `(c & 1, (c >> 1) & 1, (c >> 2) & 1)` from the cell's lowest node.
//! Edge `4 * axis + bu + 2 * bv` runs along `axis` starting at offsets `(bu, bv)` on the two plane
//! axes of [`plane_axes`]. Face `2 * axis + side` lies at offset `side` along `axis`.

/// Offsets (0 or 1 per axis) of corner `c`.
pub(crate) const fn corner_offset(c: usize) -> [usize; 3] {
    [c & 1, (c >> 1) & 1, (c >> 2) & 1]
}

const fn corner_index(o: [usize; 3]) -> usize {
    o[0] | (o[1] << 1) | (o[2] << 2)
}

/// The two axes spanning the plane normal to `axis`, ordered so that `u x v` points along `axis`.
pub(crate) const fn plane_axes(axis: usize) -> (usize, usize) {
    ((axis + 1) % 3, (axis + 2) % 3)
}

/// Axis along which edge `e` runs.
pub(crate) const fn edge_axis(e: usize) -> usize {
    e / 4
}

/// Corner offsets of the lower end of edge `e`.
pub(crate) const fn edge_start(e: usize) -> [usize; 3] {
    let (u, v) = plane_axes(edge_axis(e));
    let mut o = [0; 3];
    o[u] = e & 1;
    o[v] = (e >> 1) & 1;
    o
}

/// Lower ends of all edges, for the extractor's inner loop.
pub(crate) const EDGE_START: [[usize; 3]; 12] = {
    let mut out = [[0; 3]; 12];
    let mut e = 0;
    while e < 12 {
        out[e] = edge_start(e);
        e += 1;
    }
    out
};

/// The cube edge joining two corners that differ along exactly one axis.
const fn edge_between(a: usize, b: usize) -> usize {
    let axis = (a ^ b).trailing_zeros() as usize;
    let lo = if a < b { a } else { b };
    let o = corner_offset(lo);
    let (u, v) = plane_axes(axis);
    4 * axis + o[u] + 2 * o[v]
}

/// Corners of face `f` in counter-clockwise order seen from outside the cube.
pub(crate) const fn face_corners(f: usize) -> [usize; 4] {
    let axis = f / 2;
    let side = f & 1;
    let (u, v) = plane_axes(axis);
    // Stepping (0,0) (1,0) (1,1) (0,1) in (u, v) turns counter-clockwise about +axis; the face
    // at side 0 looks along -axis, so it walks the square the other way round.
    let steps: [[usize; 2]; 4] = if side == 1 {
        [[0, 0], [1, 0], [1, 1], [0, 1]]
    } else {
        [[0, 0], [0, 1], [1, 1], [1, 0]]
    };
    let mut out = [0; 4];
    let mut i = 0;
    while i < 4 {
        let mut o = [0; 3];
        o[axis] = side;
        o[u] = steps[i][0];
        o[v] = steps[i][1];
        out[i] = corner_index(o);
        i += 1;
    }
    out
}

/// Edges of face `f`: edge `i` joins counter-clockwise corners `i` and `i + 1`.
pub(crate) const fn face_edges(f: usize) -> [usize; 4] {
    let c = face_corners(f);
    [
        edge_between(c[0], c[1]),
        edge_between(c[1], c[2]),
        edge_between(c[2], c[3]),
        edge_between(c[3], c[0]),
    ]
}

/// The two faces containing edge `e`.
pub(crate) const fn edge_faces(e: usize) -> [usize; 2] {
    let (u, v) = plane_axes(edge_axis(e));
    let s = edge_start(e);
    [2 * u + s[u], 2 * v + s[v]]
}

/// Whether two distinct edges lie on a common face.
pub(crate) const fn share_face(a: usize, b: usize) -> bool {
    let fa = edge_faces(a);
    let fb = edge_faces(b);
    fa[0] == fb[0] || fa[0] == fb[1] || fa[1] == fb[0] || fa[1] == fb[1]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pos(c: usize) -> [i32; 3] {
        corner_offset(c).map(|x| x as i32)
    }

    #[test]
    fn faces_wind_counter_clockwise_about_outward_normal() {
        for f in 0..6 {
            let c = face_corners(f).map(pos);
            let d1: Vec<i32> = (0..3).map(|k| c[1][k] - c[0][k]).collect();
            let d2: Vec<i32> = (0..3).map(|k| c[2][k] - c[1][k]).collect();
            let n = [
                d1[1] * d2[2] - d1[2] * d2[1],
                d1[2] * d2[0] - d1[0] * d2[2],
                d1[0] * d2[1] - d1[1] * d2[0],
            ];
            let mut outward = [0; 3];
            outward[f / 2] = if f & 1 == 1 { 1 } else { -1 };
            assert_eq!(n, outward, "face {f}");
        }
    }

    #[test]
    fn every_edge_is_used_once_in_each_direction_by_the_faces() {
        let mut uses = std::collections::HashMap::new();
        for f in 0..6 {
            let c = face_corners(f);
            for i in 0..4 {
                *uses.entry((c[i], c[(i + 1) % 4])).or_insert(0) += 1;
            }
            for (i, &e) in face_edges(f).iter().enumerate() {
                let mut ends = edge_start(e);
                let a = corner_index(ends);
                ends[edge_axis(e)] = 1;
                let b = corner_index(ends);
                let (x, y) = (c[i], c[(i + 1) % 4]);
                assert!((a, b) == (x, y) || (a, b) == (y, x));
                assert!(edge_faces(e).contains(&f));
            }
        }
        assert_eq!(uses.len(), 24);
        for (&(a, b), &n) in &uses {
            assert_eq!(n, 1);
            assert_eq!(uses.get(&(b, a)), Some(&1));
        }
    }
}
