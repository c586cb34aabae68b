//! Splitting the dual quads into triangles.

use glam::Vec3;

/// Shape quality of triangle `a b c` facing `dir`: twice its area projected on `dir` over the
/// sum of squared sides, so it is largest for equilateral triangles, zero for degenerate ones
/// and negative for triangles facing away from `dir`.
#[inline]
fn quality(a: Vec3, b: Vec3, c: Vec3, dir: Vec3) -> f32 {
    let n = (b - a).cross(c - a);
    let sides = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    n.dot(dir) / sides
}

/// Triangles (as corner indices 0..4) of the quad `p` (in winding order), split along the
/// diagonal whose worse triangle is better shaped and facing `dir`. When the quad's corners
/// project onto the plane normal to `dir` as a simple polygon, one diagonal always gives two
/// triangles facing `dir`, so the choice never produces a flipped or degenerate triangle when
/// the other does not.
pub(crate) fn split_quad(p: [Vec3; 4], dir: Vec3) -> [[usize; 3]; 2] {
    let first = quality(p[0], p[1], p[2], dir).min(quality(p[0], p[2], p[3], dir));
    let second = quality(p[1], p[2], p[3], dir).min(quality(p[1], p[3], p[0], dir));
    if second > first {
        [[1, 2, 3], [1, 3, 0]]
    } else {
        [[0, 1, 2], [0, 2, 3]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn avoids_the_diagonal_outside_a_concave_quad() {
        // An arrowhead with its reflex corner at 2: the diagonal 1-3 lies outside the quad.
        let p = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.4, 0.0),
            Vec3::new(0.0, 0.3, 0.0),
            Vec3::new(-1.0, 0.4, 0.0),
        ];
        let tris = split_quad(p, Vec3::Z);
        for t in tris {
            let n = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
            assert!(n.z > 0.0, "{tris:?}");
        }
    }

    #[test]
    fn prefers_the_short_diagonal_of_a_rhombus() {
        let p = [
            Vec3::new(-2.0, 0.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        assert_eq!(split_quad(p, Vec3::Z)[0], [1, 2, 3]);
    }
}
