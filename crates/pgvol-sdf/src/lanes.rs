//! Squared distances from a point to four consecutive triangles at once.
//!
//! The corners are stored as a structure of arrays, and every lane repeats the arithmetic of
//! [`closest_point`](crate::triangle::closest_point) operation for operation, so the distances
//! are bit-identical to it. A scan compares four triangles per step without branching on the
//! Voronoi region and asks the scalar code only about the triangles that improve.

use glam::{BVec4A, Vec3A, Vec4};

/// Triangles per step.
pub const LANES: usize = 4;

/// Corners of the triangles in leaf order, one array per corner and axis, padded so that a
/// step starting at any triangle stays in bounds.
#[derive(Clone, Debug, Default)]
pub struct TriangleLanes {
    corners: [[Vec<f32>; 3]; 3],
}

/// Three lanes of coordinates: four points.
#[derive(Clone, Copy)]
struct V4 {
    x: Vec4,
    y: Vec4,
    z: Vec4,
}

impl V4 {
    fn splat(p: Vec3A) -> V4 {
        V4 {
            x: Vec4::splat(p.x),
            y: Vec4::splat(p.y),
            z: Vec4::splat(p.z),
        }
    }

    fn sub(self, o: V4) -> V4 {
        V4 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }

    fn add(self, o: V4) -> V4 {
        V4 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }

    fn scale(self, t: Vec4) -> V4 {
        V4 {
            x: self.x * t,
            y: self.y * t,
            z: self.z * t,
        }
    }

    /// `(x·x' + y·y') + z·z'`, the order of glam's `Vec3A::dot`.
    fn dot(self, o: V4) -> Vec4 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    fn select(mask: BVec4A, t: V4, f: V4) -> V4 {
        V4 {
            x: Vec4::select(mask, t.x, f.x),
            y: Vec4::select(mask, t.y, f.y),
            z: Vec4::select(mask, t.z, f.z),
        }
    }
}

impl TriangleLanes {
    pub fn new(tris: &[[Vec3A; 3]]) -> TriangleLanes {
        let mut corners: [[Vec<f32>; 3]; 3] = Default::default();
        for (c, axes) in corners.iter_mut().enumerate() {
            for (axis, values) in axes.iter_mut().enumerate() {
                values.extend(tris.iter().map(|t| t[c][axis]));
                values.extend([0.0; LANES - 1]);
            }
        }
        TriangleLanes { corners }
    }

    fn corner(&self, c: usize, start: usize) -> V4 {
        let lane = |axis: usize| Vec4::from_slice(&self.corners[c][axis][start..start + LANES]);
        V4 {
            x: lane(0),
            y: lane(1),
            z: lane(2),
        }
    }

    /// Squared distances from `p` to the triangles at `start .. start + LANES` (lanes past the
    /// last triangle hold padding). A lane is NaN where the scalar code would fall back to
    /// the edges of a degenerate triangle: the caller asks it.
    #[inline]
    pub fn distances_squared(&self, p: Vec3A, start: usize) -> Vec4 {
        let zero = Vec4::ZERO;
        let (a, b, c) = (
            self.corner(0, start),
            self.corner(1, start),
            self.corner(2, start),
        );
        let p = V4::splat(p);
        let ab = b.sub(a);
        let ac = c.sub(a);
        let ap = p.sub(a);
        let d1 = ab.dot(ap);
        let d2 = ac.dot(ap);
        let bp = p.sub(b);
        let d3 = ab.dot(bp);
        let d4 = ac.dot(bp);
        let vc = d1 * d4 - d3 * d2;
        let cp = p.sub(c);
        let d5 = ab.dot(cp);
        let d6 = ac.dot(cp);
        let vb = d5 * d2 - d1 * d6;
        let va = d3 * d6 - d5 * d4;
        let (d43, d56) = (d4 - d3, d5 - d6);
        // The regions in the scalar code's order; the first that holds wins, so they are
        // applied last to first.
        let vertex_a = d1.cmple(zero) & d2.cmple(zero);
        let vertex_b = d3.cmpge(zero) & d4.cmple(d3);
        let edge_ab = vc.cmple(zero) & d1.cmpge(zero) & d3.cmple(zero);
        let vertex_c = d6.cmpge(zero) & d5.cmple(d6);
        let edge_ac = vb.cmple(zero) & d2.cmpge(zero) & d6.cmple(zero);
        let edge_bc = va.cmple(zero) & d43.cmpge(zero) & d56.cmpge(zero);
        let sum = va + vb + vc;
        let denom = Vec4::ONE / sum;
        let face = a.add(ab.scale(vb * denom)).add(ac.scale(vc * denom));
        let mut q = face;
        q = V4::select(edge_bc, b.add(c.sub(b).scale(d43 / (d43 + d56))), q);
        q = V4::select(edge_ac, a.add(ac.scale(d2 / (d2 - d6))), q);
        q = V4::select(vertex_c, c, q);
        q = V4::select(edge_ab, a.add(ab.scale(d1 / (d1 - d3))), q);
        q = V4::select(vertex_b, b, q);
        q = V4::select(vertex_a, a, q);
        let pq = p.sub(q);
        let distance = pq.dot(pq);
        let regions = vertex_a | vertex_b | edge_ab | vertex_c | edge_ac | edge_bc;
        let degenerate = !(sum.cmpgt(zero) & sum.cmplt(Vec4::INFINITY)) & !regions;
        Vec4::select(degenerate, Vec4::NAN, distance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::closest_point;
    use rand::{Rng, SeedableRng};

    #[test]
    fn lanes_are_bit_identical_to_the_scalar_distance() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
        let mut point = |scale: f32| {
            Vec3A::new(rng.gen::<f32>(), rng.gen::<f32>(), rng.gen::<f32>()) * scale - 0.5 * scale
        };
        let mut tris: Vec<[Vec3A; 3]> = (0..400)
            .map(|_| [point(1.0), point(1.0), point(1.0)])
            .collect();
        // Degenerate ones: a point, a segment, collinear corners.
        let (a, b) = (point(1.0), point(1.0));
        tris.extend([[a, a, a], [a, b, b], [a, b, a + (b - a) * 2.0]]);
        let lanes = TriangleLanes::new(&tris);
        let mut degenerate = 0;
        for _ in 0..300 {
            let p = point(3.0);
            for start in (0..tris.len()).step_by(LANES) {
                let got = lanes.distances_squared(p, start).to_array();
                for (l, &d2) in got.iter().enumerate().take(tris.len() - start) {
                    let [a, b, c] = tris[start + l];
                    let want = p.distance_squared(closest_point(p, a, b, c).0);
                    if d2.is_nan() {
                        degenerate += 1;
                    } else {
                        assert_eq!(d2.to_bits(), want.to_bits(), "triangle {}", start + l);
                    }
                }
            }
        }
        assert!(
            degenerate < 300 * 3,
            "{degenerate} lanes left to the scalar code"
        );
    }
}
