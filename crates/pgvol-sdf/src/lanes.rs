//! Squared distances from a point to several triangles at once (four, or eight in the grid
//! scans).
//!
//! The corners are stored as a structure of arrays, and every lane repeats the arithmetic of
//! [`closest_point`](crate::triangle::closest_point) operation for operation, so the distances
//! are bit-identical to it. A scan compares several triangles per step without branching on the
//! Voronoi region and asks the scalar code only about the triangles that improve.

use glam::{Vec3A, Vec4};

use crate::wide::Wide;

/// Triangles per step of [`TriangleLanes::distances_squared`].
pub const LANES: usize = 4;

/// The widest step any scan takes: the padding after the last triangle.
const WIDEST: usize = 8;

/// Corners of the triangles in leaf order, one run of `stride` floats per corner and axis (the
/// triangles, then padding so that a step starting at any triangle stays in the run). One
/// buffer lets a step check its bounds once instead of once per load.
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
    fn add(self, o: Self) -> Self {
        Points {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
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

    #[inline(always)]
    fn select(mask: W::Mask, t: Self, f: Self) -> Self {
        Points {
            x: W::select(mask, t.x, f.x),
            y: W::select(mask, t.y, f.y),
            z: W::select(mask, t.z, f.z),
        }
    }
}

impl TriangleLanes {
    pub fn new(tris: &[[Vec3A; 3]]) -> TriangleLanes {
        let stride = tris.len() + WIDEST - 1;
        let mut values = Vec::with_capacity(9 * stride);
        for c in 0..3 {
            for axis in 0..3 {
                values.extend(tris.iter().map(|t| t[c][axis]));
                values.extend([0.0; WIDEST - 1]);
            }
        }
        TriangleLanes { values, stride }
    }

    /// Panics unless a step of `W::LANES` triangles from `start` stays in the runs: what the
    /// unchecked loads of [`TriangleLanes::corner`] need.
    #[inline(always)]
    fn check_step<W: Wide>(&self, start: usize) {
        assert!(
            start + W::LANES <= self.stride,
            "triangle step out of bounds"
        );
    }

    // No closures in the kernels: a closure is not always inlined into its caller, and
    // outside the AVX2 build its wide operations become calls.
    /// Corner `c` of the triangles `start .. start + W::LANES`.
    ///
    /// # Safety
    /// [`TriangleLanes::check_step`] passed for `start`.
    #[inline(always)]
    unsafe fn corner<W: Wide>(&self, c: usize, start: usize) -> Points<W> {
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
        let (a, b, c) = unsafe {
            (
                self.corner::<W>(0, start),
                self.corner::<W>(1, start),
                self.corner::<W>(2, start),
            )
        };
        distances_to_corners(p, [a, b, c])
    }
}

/// The kernel of [`TriangleLanes::distances_squared`] on triangles with corners `a`, `b`, `c`.
#[inline(always)]
fn distances_to_corners<W: Wide>(p: Vec3A, [a, b, c]: [Points<W>; 3]) -> W {
    let zero = W::splat(0.0);
    let p = Points::<W>::splat(p);
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
    let vertex_a = d1.le(zero) & d2.le(zero);
    let vertex_b = d3.ge(zero) & d4.le(d3);
    let edge_ab = vc.le(zero) & d1.ge(zero) & d3.le(zero);
    let vertex_c = d6.ge(zero) & d5.le(d6);
    let edge_ac = vb.le(zero) & d2.ge(zero) & d6.le(zero);
    let edge_bc = va.le(zero) & d43.ge(zero) & d56.ge(zero);
    let sum = va + vb + vc;
    // Each lane uses one quotient: the face's `1 / sum` or its edge's parameter. Dividing
    // once by per-lane operands gives the same bits as the four divisions.
    let mut numerator = W::splat(1.0);
    let mut denominator = sum;
    for (edge, n, d) in [
        (edge_bc, d43, d43 + d56),
        (edge_ac, d2, d2 - d6),
        (edge_ab, d1, d1 - d3),
    ] {
        numerator = W::select(edge, n, numerator);
        denominator = W::select(edge, d, denominator);
    }
    let quotient = numerator / denominator;
    let face = a.add(ab.scale(vb * quotient)).add(ac.scale(vc * quotient));
    let mut q = face;
    q = Points::select(edge_bc, b.add(c.sub(b).scale(quotient)), q);
    q = Points::select(edge_ac, a.add(ac.scale(quotient)), q);
    q = Points::select(vertex_c, c, q);
    q = Points::select(edge_ab, a.add(ab.scale(quotient)), q);
    q = Points::select(vertex_b, b, q);
    q = Points::select(vertex_a, a, q);
    let pq = p.sub(q);
    let distance = pq.dot(pq);
    let regions = vertex_a | vertex_b | edge_ab | vertex_c | edge_ac | edge_bc;
    let degenerate = !(sum.gt(zero) & sum.lt(W::splat(f32::INFINITY))) & !regions;
    W::select(degenerate, W::splat(f32::NAN), distance)
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
