//! Exact closest point on a triangle, classified by the feature (face, edge, vertex) it lies on.

use glam::Vec3A;

/// Which part of a triangle holds the closest point; the pseudonormal sign needs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feature {
    Face,
    /// Edge from corner `n` to corner `(n + 1) % 3`.
    Edge(u8),
    Vertex(u8),
}

/// Closest point on triangle `(a, b, c)` to `p`, by the Voronoi regions of its features.
/// Degenerate triangles (zero area) fall through to their edges and stay exact.
#[inline(always)]
pub fn closest_point(p: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> (Vec3A, Feature) {
    let (point, feature, _) = closest_point_and_distance(p, a, b, c);
    (point, feature)
}

/// [`closest_point`] with the squared distance to it.
///
/// The regions are told apart by the dot products of the edges `ab`, `ac` with `ap`, `bp`, `cp`;
/// those with `bp = ap − ab` and `cp = ap − ac` come from the first two and the edges' own dot
/// products, which the grid scans keep per triangle. The face's barycentric weights are triple
/// products with the normal `n` ([`normal`], worked out in f64): `vc = ap · (n × ab)`,
/// `vb = ap · (ac × n)` and the third `n · n` less both, not differences of products of dot
/// products. For a sliver (two long, nearly parallel edges, as a CAD cylinder's side faces
/// are) those cancel, and the face is lost to a neighbour's edge far away. On the face the
/// distance is the plane's, `(n · ap)² / (n · n)`, taken as `h · (h / n · n)` for `h = n · ap`;
/// elsewhere it is the length of `ap − s·ab − t·ac` for the closest point's coordinates `(s, t)`
/// along the edges (accurate for small triangles far from the origin). The grid scans' kernel
/// (`lanes.rs`) repeats this arithmetic operation for operation.
// Inlined into the scans: a call per triangle measured 10 % slower on dense grids.
#[inline(always)]
pub fn closest_point_and_distance(p: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> (Vec3A, Feature, f32) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let offset = |s: f32, t: f32| {
        let pq = ap - ab * s - ac * t;
        pq.dot(pq)
    };
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0), offset(0.0, 0.0));
    }
    let (e11, e12, e22) = (ab.dot(ab), ab.dot(ac), ac.dot(ac));
    let d3 = d1 - e11;
    let d4 = d2 - e12;
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1), offset(1.0, 0.0));
    }
    let n = normal(a, b, c);
    let vc = ap.dot(cross(n, ab));
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let t = d1 / (d1 - d3);
        return (a + ab * t, Feature::Edge(0), offset(t, 0.0));
    }
    let d5 = d1 - e12;
    let d6 = d2 - e22;
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2), offset(0.0, 1.0));
    }
    let vb = ap.dot(cross(ac, n));
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let t = d2 / (d2 - d6);
        return (a + ac * t, Feature::Edge(2), offset(0.0, t));
    }
    let nn = n.dot(n);
    let va = nn - vb - vc;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * t, Feature::Edge(1), offset(1.0 - t, t));
    }
    if nn.is_nan() || nn <= 0.0 || nn.is_infinite() {
        // Degenerate (collinear) triangle that slipped through the region tests: take the best edge.
        let (point, feature) = closest_on_edges(p, a, b, c);
        return (point, feature, p.distance_squared(point));
    }
    // `h · (h / n·n)`, not `h² / n·n`: `h²` goes as the sixth power of the triangle's size
    // and would leave the f32 range at the extremes of the accepted scales.
    let h = n.dot(ap);
    let along = h / nn;
    (p - n * along, Feature::Face, h * along)
}

/// `(b − a) × (c − a)` worked out in f64 and rounded: in f32 the cross product of a sliver's
/// two long edges cancels, and its direction errs by the rounding of their length over the
/// width between them (0.03 of a distance along a 1,000-long edge, measured).
#[inline]
pub fn normal(a: Vec3A, b: Vec3A, c: Vec3A) -> Vec3A {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    (b - a).cross(c - a).as_vec3a()
}

/// `u × v`, each coordinate as the grid scans' kernel computes it.
#[inline(always)]
pub(crate) fn cross(u: Vec3A, v: Vec3A) -> Vec3A {
    Vec3A::new(
        u.y * v.z - u.z * v.y,
        u.z * v.x - u.x * v.z,
        u.x * v.y - u.y * v.x,
    )
}

fn closest_on_segment(p: Vec3A, a: Vec3A, b: Vec3A) -> Vec3A {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= 0.0 {
        return a;
    }
    let t = ((p - a).dot(ab) / len2).clamp(0.0, 1.0);
    a + ab * t
}

fn closest_on_edges(p: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> (Vec3A, Feature) {
    let candidates = [
        (closest_on_segment(p, a, b), Feature::Edge(0)),
        (closest_on_segment(p, b, c), Feature::Edge(1)),
        (closest_on_segment(p, c, a), Feature::Edge(2)),
    ];
    let mut best = candidates[0];
    for cand in &candidates[1..] {
        if p.distance_squared(cand.0) < p.distance_squared(best.0) {
            best = *cand;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v(x: f32, y: f32, z: f32) -> Vec3A {
        Vec3A::new(x, y, z)
    }

    /// Dense sampling of the triangle by barycentric coordinates: an independent upper bound.
    fn brute_force_distance(p: Vec3A, a: Vec3A, b: Vec3A, c: Vec3A) -> f32 {
        let n = 200;
        let mut best = f32::INFINITY;
        for i in 0..=n {
            for j in 0..=(n - i) {
                let u = i as f32 / n as f32;
                let w = j as f32 / n as f32;
                let q = a + (b - a) * u + (c - a) * w;
                best = best.min(p.distance(q));
            }
        }
        best
    }

    #[test]
    fn regions_of_a_right_triangle() {
        let (a, b, c) = (v(0., 0., 0.), v(1., 0., 0.), v(0., 1., 0.));
        let (q, f) = closest_point(v(0.2, 0.2, 1.0), a, b, c);
        assert!((q - v(0.2, 0.2, 0.0)).length() < 1e-6);
        assert_eq!(f, Feature::Face);
        assert_eq!(
            closest_point(v(-1., -1., 0.), a, b, c).1,
            Feature::Vertex(0)
        );
        assert_eq!(closest_point(v(2., -1., 0.), a, b, c).1, Feature::Vertex(1));
        assert_eq!(closest_point(v(-1., 3., 0.), a, b, c).1, Feature::Vertex(2));
        assert_eq!(
            closest_point(v(0.5, -1., 0.), a, b, c),
            (v(0.5, 0., 0.), Feature::Edge(0))
        );
        assert_eq!(
            closest_point(v(1., 1., 0.), a, b, c),
            (v(0.5, 0.5, 0.), Feature::Edge(1))
        );
        assert_eq!(
            closest_point(v(-1., 0.5, 0.), a, b, c),
            (v(0., 0.5, 0.), Feature::Edge(2))
        );
    }

    #[test]
    fn degenerate_triangles_are_exact() {
        let (a, b, c) = (v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.));
        let (q, _) = closest_point(v(1.5, 1.0, 0.0), a, b, c);
        assert!((q - v(1.5, 0., 0.)).length() < 1e-6);
        let (q, _) = closest_point(v(1.0, 1.0, 1.0), a, a, a);
        assert_eq!(q, a);
    }

    /// Slivers, as a CAD cylinder's side faces are (two edges hundreds of times longer than the
    /// width between them), with points just off the face anywhere along them: the distance is
    /// the plane's, worked out in f64 from the same f32 corners. Dot-product differences lost
    /// the face of such a triangle 0.05 away from a point 0.008 off it.
    #[test]
    fn slivers_keep_their_face() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let mut worst = 0.0f64;
        for _ in 0..2000 {
            let length = rng.gen_range(10.0f32..1000.0);
            let width = length * rng.gen_range(1e-4f32..1e-2);
            let along = Vec3A::new(rng.gen(), rng.gen(), rng.gen()).normalize_or_zero() + 0.01;
            let along = along.normalize();
            let across = along.any_orthogonal_vector().normalize();
            let normal = along.cross(across);
            let a = Vec3A::new(rng.gen(), rng.gen(), rng.gen()) * 100.0;
            let b = a + along * length;
            let c = b + across * width;
            // A point over the face, clear of its edges, a little off the plane.
            let (u, v) = (rng.gen_range(0.05f32..0.9), rng.gen_range(0.05f32..0.9));
            let inside = a + (b - a) * (u * (1.0 - 0.5 * v)) + (c - a) * (u * 0.5 * v);
            let p = inside + normal * (width * rng.gen_range(-0.5f32..0.5));
            let got = closest_point_and_distance(p, a, b, c).2.sqrt() as f64;
            let d = |q: Vec3A| q.as_dvec3();
            let n = (d(b) - d(a)).cross(d(c) - d(a));
            let want = (n.dot(d(p) - d(a)) / n.length()).abs();
            // The f32 corners and point carry rounding of their own size.
            let scale = (length + a.length()) as f64 * 1e-6;
            worst = worst.max((got - want).abs() / scale);
        }
        assert!(worst < 1.0, "worst error {worst} millionths of the size");
    }

    /// The rod's side face from `pgvol encode` at 4096³ (a 32-sided prism of radius 1 and
    /// length 200): a point 0.0078 outside it at z = 170 is 0.0078 from its nearer triangle.
    #[test]
    fn a_long_prism_side_is_found_at_its_far_end() {
        let corner = |k: f32, z: f32| {
            let t = 2.0 * std::f32::consts::PI * k / 32.0;
            Vec3A::new(t.cos(), t.sin(), z)
        };
        let p = Vec3A::new(-0.4595, -0.8917, 170.0);
        let best = (0..32)
            .flat_map(|k| {
                let k = k as f32;
                let (a, b) = (corner(k, 0.0), corner(k + 1.0, 0.0));
                let (c, d) = (corner(k + 1.0, 200.0), corner(k, 200.0));
                [(a, b, c), (a, c, d)]
            })
            .map(|(a, b, c)| closest_point_and_distance(p, a, b, c).2.sqrt())
            .fold(f32::INFINITY, f32::min);
        assert!((best - 0.007_831).abs() < 1e-4, "{best}");
    }

    proptest! {
        #[test]
        fn never_farther_than_brute_force(
            t in proptest::array::uniform9(-1.0f32..1.0),
            p in proptest::array::uniform3(-2.0f32..2.0),
        ) {
            let (a, b, c) = (v(t[0], t[1], t[2]), v(t[3], t[4], t[5]), v(t[6], t[7], t[8]));
            let p = v(p[0], p[1], p[2]);
            let (q, _) = closest_point(p, a, b, c);
            let d = p.distance(q);
            let brute = brute_force_distance(p, a, b, c);
            // The sampled minimum is an upper bound within the sampling step of the true minimum.
            let step = (b - a).length().max((c - a).length()) / 200.0;
            prop_assert!(d <= brute + 1e-5);
            prop_assert!(d >= brute - step - 1e-5);
            // The distance is the returned point's, up to rounding at the triangle's scale.
            let (_, _, d2) = closest_point_and_distance(p, a, b, c);
            let scale = (p - a).length() + (b - a).length() + (c - a).length();
            prop_assert!((d2.sqrt() - d).abs() <= 1e-5 * scale, "{} against {d}", d2.sqrt());
            // The returned point lies in the triangle's plane region: barycentrics are in [0, 1].
            let n = (b - a).cross(c - a);
            if n.length() > 1e-3 {
                prop_assert!((q - a).dot(n).abs() / n.length() < 1e-4);
            }
        }
    }
}
