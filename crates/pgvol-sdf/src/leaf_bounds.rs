//! Oriented boxes around the BVH's leaves: a lower bound on the distance from a point to a
//! leaf's triangles that is far tighter than the leaf's axis-aligned box when the leaf is a
//! small, tilted, nearly flat patch of surface (the box of such a patch is fat in every axis,
//! the oriented box is thin along the patch's normal).
//!
//! To keep the grid scans' copies small, a box stores two axes and its half extents only: it is
//! centred on the leaf's axis-aligned box, and its third axis is the cross product of the other
//! two, both computed by [`centre_of`] and [`third_axis`] wherever the box is used.

use glam::Vec3A;

/// The points `x` with `|axis_i · (x − centre)| <= half[i]`, for the axes `first`, `second` and
/// their cross product (orthonormal up to rounding) and the centre of the leaf's axis-aligned
/// box.
#[derive(Clone, Copy, Debug)]
pub struct OrientedBox {
    pub first: [f32; 3],
    pub second: [f32; 3],
    pub half: [f32; 3],
}

/// Slack that makes [`OrientedBox::distance_squared_bound`] a lower bound on the distances
/// the scans compute, not only on exact ones.
///
/// * The scans' closest point on a triangle is a convex combination of its corners up to a few
///   roundings of the corners' coordinates: it may leave the box by a few ulps of the leaf's
///   largest coordinate, far less than `SCALE_MARGIN` of it.
/// * The bound's own arithmetic errs by a few ulps of `|p − centre|`. Where `|p − centre|` is
///   within a few box sizes, that is below `EXTENT_MARGIN` of the box's size; farther out, the
///   bound is at least a third of `|p − centre|`, so the error is a few ulps of the bound itself,
///   which `SHRINK` covers together with the rounding of the squared distances.
/// * Axes orthonormal only up to rounding stretch the gap vector by a relative 1e-6 at most
///   (the gaps are at most the coordinates of `A·(p − x)` for any `x` in the box, and the axes'
///   matrix `A` has norm 1 + O(ulp)), which `SHRINK` covers too.
const SCALE_MARGIN: f64 = 4e-6;
const EXTENT_MARGIN: f64 = 1e-5;
pub(crate) const SHRINK: f32 = 1.0 - 1e-4;

/// The centre of the box `[min, max]`, as every user of an [`OrientedBox`] computes it.
#[inline(always)]
pub fn centre_of(min: Vec3A, max: Vec3A) -> Vec3A {
    (min + max) * 0.5
}

/// The cross product `a × b`, operation for operation as the wide scans compute it.
#[inline(always)]
pub fn third_axis(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl OrientedBox {
    /// A box that bounds nothing away: every distance bound is 0.
    pub const EVERYWHERE: OrientedBox = OrientedBox {
        first: [1.0, 0.0, 0.0],
        second: [0.0, 1.0, 0.0],
        half: [f32::INFINITY; 3],
    };

    /// The box around `tris`, whose axis-aligned box is `[min, max]`, along the principal axes
    /// of their corners (the thinnest along the normal of a flat patch), widened by the margins
    /// above.
    pub fn around(tris: &[[Vec3A; 3]], min: Vec3A, max: Vec3A) -> OrientedBox {
        if tris.is_empty() {
            return OrientedBox::EVERYWHERE;
        }
        let corners = || tris.iter().flatten().map(|c| c.to_array().map(f64::from));
        let n = (tris.len() * 3) as f64;
        let mut mean = [0.0f64; 3];
        for c in corners() {
            (0..3).for_each(|i| mean[i] += c[i] / n);
        }
        let mut covariance = [[0.0f64; 3]; 3];
        for c in corners() {
            let d = [c[0] - mean[0], c[1] - mean[1], c[2] - mean[2]];
            for i in 0..3 {
                for j in 0..3 {
                    covariance[i][j] += d[i] * d[j];
                }
            }
        }
        let vectors = eigenvectors(covariance);
        let unit = |i: usize| {
            let a = Vec3A::new(
                vectors[0][i] as f32,
                vectors[1][i] as f32,
                vectors[2][i] as f32,
            );
            a.normalize_or_zero().to_array()
        };
        let (mut first, mut second) = (unit(0), unit(1));
        let mut axes = [first, second, third_axis(first, second)];
        let length = |a: [f32; 3]| Vec3A::from_array(a).length();
        if axes.iter().any(|&a| !(0.999..=1.001).contains(&length(a))) {
            (first, second) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
            axes = [first, second, third_axis(first, second)];
        }
        // Extents along the axes the bound uses about the centre it uses, in f64 so that they
        // are exact enough.
        let centre = centre_of(min, max).to_array().map(f64::from);
        let mut half = [0.0f64; 3];
        let mut scale = 0.0f64;
        for c in corners() {
            for (i, axis) in axes.iter().enumerate() {
                let along: f64 = (0..3)
                    .map(|k| (c[k] - centre[k]) * f64::from(axis[k]))
                    .sum();
                half[i] = half[i].max(along.abs());
            }
            scale = c.iter().fold(scale, |s, x| s.max(x.abs()));
        }
        let extent = half.iter().fold(0.0f64, |e, &h| e.max(2.0 * h));
        let margin = SCALE_MARGIN * scale + EXTENT_MARGIN * extent;
        OrientedBox {
            first,
            second,
            half: half.map(|h| (h + margin) as f32),
        }
    }

    /// A lower bound on the squared distance from `p` to any triangle inside the box, whose
    /// leaf's axis-aligned box is `[min, max]`: the squared length of how far `p` lies outside
    /// the box along each axis, shrunk by [`SHRINK`].
    pub fn distance_squared_bound(&self, p: Vec3A, min: Vec3A, max: Vec3A) -> f32 {
        let d = p - centre_of(min, max);
        let axes = [self.first, self.second, third_axis(self.first, self.second)];
        let mut sum = 0.0;
        for (axis, half) in axes.iter().zip(self.half) {
            let along = d.x * axis[0] + d.y * axis[1] + d.z * axis[2];
            let gap = (along - half).max(-along - half).max(0.0);
            sum += gap * gap;
        }
        sum * SHRINK
    }
}

/// Eigenvectors of the symmetric matrix `m`, as the columns of the result, by cyclic Jacobi
/// rotations (which keep them orthonormal to rounding whatever the spectrum).
fn eigenvectors(mut m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let diagonal = m[0][0].abs() + m[1][1].abs() + m[2][2].abs();
    for _ in 0..32 {
        let off = m[0][1].abs() + m[0][2].abs() + m[1][2].abs();
        if off <= 1e-15 * diagonal {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if m[p][q] == 0.0 {
                continue;
            }
            let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in m.iter_mut().chain(v.iter_mut()) {
                let (rp, rq) = (row[p], row[q]);
                row[p] = c * rp - s * rq;
                row[q] = s * rp + c * rq;
            }
            let (mp, mq) = (m[p], m[q]);
            m[p] = [0, 1, 2].map(|k| c * mp[k] - s * mq[k]);
            m[q] = [0, 1, 2].map(|k| s * mp[k] + c * mq[k]);
        }
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_leaves_get_thin_boxes() {
        let tilted = |x: f32, y: f32| Vec3A::new(x, y, 0.3 * x + 0.6 * y);
        let tris = [
            [tilted(0.0, 0.0), tilted(1.0, 0.0), tilted(0.0, 1.0)],
            [tilted(1.0, 0.0), tilted(1.0, 1.0), tilted(0.0, 1.0)],
        ];
        let corners = tris.iter().flatten();
        let min = corners.clone().fold(Vec3A::INFINITY, |m, &c| m.min(c));
        let max = corners.fold(Vec3A::NEG_INFINITY, |m, &c| m.max(c));
        let oriented = OrientedBox::around(&tris, min, max);
        assert!(oriented.half.iter().any(|&h| h < 1e-4));
        // Above the middle of the patch, along its normal: the axis-aligned box holds the point.
        let normal = Vec3A::new(-0.3, -0.6, 1.0).normalize();
        let p = tilted(0.5, 0.5) + normal * 0.2;
        assert!(p.cmple(max).all() && p.cmpge(min).all());
        let bound = oriented.distance_squared_bound(p, min, max);
        assert!((bound.sqrt() - 0.2).abs() < 1e-3, "{bound}");
    }
}
