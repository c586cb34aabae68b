//! Squared distances from a point to several triangles at once (four, or eight in the grid
//! scans).
//!
//! Each triangle is stored as its corners, its edges' dot products and its normal, as a
//! structure of arrays, and every lane repeats the arithmetic of
//! [`closest_point_and_distance`](crate::triangle::closest_point_and_distance) operation for
//! operation, so the distances are bit-identical to it. Keeping the dot products spares each step
//! 3 of its 6 dot products. The corners, not
//! the edges, are kept so that they are the only copy of the triangles in leaf order: the edges
//! cost a subtraction each per step, and the copy they would need cost 48 bytes per triangle
//! (62 MB for a mesh of 1.3 M triangles). A scan compares several triangles per step without
//! branching on the Voronoi region and asks the scalar code only about the triangles that improve.

use glam::{Vec3A, Vec4};

use crate::triangle::normal;
use crate::wide::Wide;

/// Runs per triangle: corners `a`, `b` and `c` (three axes each), the edges' dot products
/// `ab·ab`, `ab·ac`, `ac·ac`, and the normal `ab × ac` ([`normal`]).
const RUNS: usize = 15;

/// Triangles per step of [`TriangleLanes::distances_squared`].
pub const LANES: usize = 4;

/// The widest step any scan takes: the padding after the last triangle.
const WIDEST: usize = 8;

/// The triangles in leaf order, one run of `stride` floats per term of [`RUNS`] (the triangles,
/// then padding so that a step starting at any triangle stays in the run). One buffer lets a
/// step check its bounds once instead of once per load.
#[derive(Clone, Debug, Default)]
pub struct TriangleLanes {
    values: Vec<f32>,
    stride: usize,
}

/// Three coordinates of `W::LANES` points.
#[derive(Clone, Copy)]
struct Points<W> {
    x: W,
    y: W,
    z: W,
}

impl<W: Wide> Points<W> {
    #[inline(always)]
    fn splat(p: Vec3A) -> Self {
        Points {
            x: W::splat(p.x),
            y: W::splat(p.y),
            z: W::splat(p.z),
        }
    }

    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Points {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }

    #[inline(always)]
    fn scale(self, t: W) -> Self {
        Points {
            x: self.x * t,
            y: self.y * t,
            z: self.z * t,
        }
    }

    /// `(x·x' + y·y') + z·z'`, the order of glam's `Vec3A::dot`.
    #[inline(always)]
    fn dot(self, o: Self) -> W {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// `self × o`, each coordinate as [`crate::triangle::cross`] computes it.
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        Points {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }
}

impl TriangleLanes {
    pub fn new(tris: &[[Vec3A; 3]]) -> TriangleLanes {
        let mut lanes = TriangleLanes::with_len(tris.len());
        for (slot, t) in tris.iter().enumerate() {
            lanes.set(slot, t);
        }
        lanes
    }

    /// Room for `len` triangles, all zero.
    pub fn with_len(len: usize) -> TriangleLanes {
        let stride = len + WIDEST - 1;
        TriangleLanes {
            values: vec![0.0; RUNS * stride],
            stride,
        }
    }

    /// The number of triangles held.
    pub fn len(&self) -> usize {
        self.stride + 1 - WIDEST
    }

    /// Stores triangle `t` at `slot`.
    pub fn set(&mut self, slot: usize, t: &[Vec3A; 3]) {
        assert!(slot < self.len(), "slot {slot} past the lanes");
        // The same arithmetic as the scalar code's, so the terms have its bits.
        let (ab, ac) = (t[1] - t[0], t[2] - t[0]);
        let (e11, e12, e22) = (ab.dot(ab), ab.dot(ac), ac.dot(ac));
        let n = normal(t[0], t[1], t[2]);
        let terms = [
            t[0].x, t[0].y, t[0].z, t[1].x, t[1].y, t[1].z, t[2].x, t[2].y, t[2].z, e11, e12, e22,
            n.x, n.y, n.z,
        ];
        for (run, v) in terms.into_iter().enumerate() {
            self.values[run * self.stride + slot] = v;
        }
    }

    /// The corners of the triangle at `slot`, as they were stored.
    #[inline]
    pub fn corners(&self, slot: usize) -> [Vec3A; 3] {
        let v = |run: usize| self.values[run * self.stride + slot];
        assert!(slot < self.len(), "slot {slot} past the lanes");
        [0, 3, 6].map(|r| Vec3A::new(v(r), v(r + 1), v(r + 2)))
    }

    /// Panics unless a step of `W::LANES` triangles from `start` stays in the runs: what the
    /// unchecked loads of [`TriangleLanes::triple`] need.
    #[inline(always)]
    fn check_step<W: Wide>(&self, start: usize) {
        assert!(
            start + W::LANES <= self.stride,
            "triangle step out of bounds"
        );
    }

    // No closures in the kernels: a closure is not always inlined into its caller, and
    // outside the AVX2 build its wide operations become calls.
    /// Runs `3 c .. 3 c + 3` (`c` = 0, 1, 2: corners `a`, `b`, `c`, 3: the dot products,
    /// 4: the normal) for the triangles `start .. start + W::LANES`.
    ///
    /// # Safety
    /// [`TriangleLanes::check_step`] passed for `start`.
    #[inline(always)]
    unsafe fn triple<W: Wide>(&self, c: usize, start: usize) -> Points<W> {
        // SAFETY: `start + LANES <= stride`, so the step stays in runs `3 c .. 3 c + 3`.
        unsafe {
            let x = self.values.as_ptr().add(3 * c * self.stride + start);
            let (y, z) = (x.add(self.stride), x.add(2 * self.stride));
            Points {
                x: W::load_unchecked(x),
                y: W::load_unchecked(y),
                z: W::load_unchecked(z),
            }
        }
    }

    /// Squared distances from `p` to the triangles at `start .. start + LANES` (lanes past the
    /// last triangle hold padding). A lane is NaN where the scalar code would fall back to
    /// the edges of a degenerate triangle: the caller asks it.
    #[inline]
    pub fn distances_squared(&self, p: Vec3A, start: usize) -> Vec4 {
        self.distances_squared_wide(p, start)
    }

    /// As [`TriangleLanes::distances_squared`], for the `W::LANES` triangles from `start`.
    #[inline(always)]
    pub(crate) fn distances_squared_wide<W: Wide>(&self, p: Vec3A, start: usize) -> W {
        self.check_step::<W>(start);
        // SAFETY: checked above.
        let (a, b, c, e, n) = unsafe {
            (
                self.triple::<W>(0, start),
                self.triple::<W>(1, start),
                self.triple::<W>(2, start),
                self.triple::<W>(3, start),
                self.triple::<W>(4, start),
            )
        };
        // The edges as the scalar code computes them.
        distances_to_triangles(p, a, b.sub(a), c.sub(a), [e.x, e.y, e.z], n)
    }
}

/// The kernel of [`TriangleLanes::distances_squared`]: triangles with corner `a`, edges `ab`,
/// `ac`, their dot products `e = [ab·ab, ab·ac, ac·ac]` and normal `n`.
#[inline(always)]
fn distances_to_triangles<W: Wide>(
    p: Vec3A,
    a: Points<W>,
    ab: Points<W>,
    ac: Points<W>,
    e: [W; 3],
    n: Points<W>,
) -> W {
    let zero = W::splat(0.0);
    let p = Points::<W>::splat(p);
    let ap = p.sub(a);
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    let d3 = d1 - e[0];
    let d4 = d2 - e[1];
    let vc = ap.dot(n.cross(ab));
    let d5 = d1 - e[1];
    let d6 = d2 - e[2];
    let vb = ap.dot(ac.cross(n));
    let nn = n.dot(n);
    let va = nn - vb - vc;
    let (d43, d56) = (d4 - d3, d5 - d6);
    // The regions in the scalar code's order; the first that holds wins, so they are
    // applied last to first.
    let vertex_a = d1.le(zero) & d2.le(zero);
    let vertex_b = d3.ge(zero) & d4.le(d3);
    let edge_ab = vc.le(zero) & d1.ge(zero) & d3.le(zero);
    let vertex_c = d6.ge(zero) & d5.le(d6);
    let edge_ac = vb.le(zero) & d2.ge(zero) & d6.le(zero);
    let edge_bc = va.le(zero) & d43.ge(zero) & d56.ge(zero);
    // Each lane uses one quotient: the face's `h / (n·n)`, whose product with `h` is the
    // squared distance to the plane, or its edge's parameter. Dividing once by per-lane
    // operands gives the same bits as the four divisions.
    let h = n.dot(ap);
    let mut numerator = h;
    let mut denominator = nn;
    for (edge, n, d) in [
        (edge_bc, d43, d43 + d56),
        (edge_ac, d2, d2 - d6),
        (edge_ab, d1, d1 - d3),
    ] {
        numerator = W::select(edge, n, numerator);
        denominator = W::select(edge, d, denominator);
    }
    let quotient = numerator / denominator;
    let one = W::splat(1.0);
    // The closest point's coordinates `(s, t)` along `ab` and `ac` off the face: an edge's
    // parameter, or a corner.
    let mut s = zero;
    let mut t = zero;
    s = W::select(edge_bc, one - quotient, s);
    t = W::select(edge_bc, quotient, t);
    s = W::select(edge_ac, zero, s);
    t = W::select(edge_ac, quotient, t);
    s = W::select(vertex_c, zero, s);
    t = W::select(vertex_c, one, t);
    s = W::select(edge_ab, quotient, s);
    t = W::select(edge_ab, zero, t);
    s = W::select(vertex_b, one, s);
    t = W::select(vertex_b, zero, t);
    s = W::select(vertex_a, zero, s);
    t = W::select(vertex_a, zero, t);
    let pq = ap.sub(ab.scale(s)).sub(ac.scale(t));
    let off_face = pq.dot(pq);
    let regions = vertex_a | vertex_b | edge_ab | vertex_c | edge_ac | edge_bc;
    let distance = W::select(regions, off_face, h * quotient);
    let degenerate = !(nn.gt(zero) & nn.lt(W::splat(f32::INFINITY))) & !regions;
    W::select(degenerate, W::splat(f32::NAN), distance)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::closest_point_and_distance;
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
                    let want = closest_point_and_distance(p, a, b, c).2;
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
