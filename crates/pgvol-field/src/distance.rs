//! What a fit is given: a signed distance with its gradient, or the closest points of the
//! surface.

use glam::Vec3;

/// A signed distance function (negative inside) with its gradient, the unit direction away from
/// the closest surface point.
pub trait SignedDistance: Sync {
    fn distance(&self, p: Vec3) -> f32;
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3);
}

/// Adapts a closure returning `(distance, gradient)` to [`SignedDistance`].
pub struct SdfFn<F>(pub F);

impl<F: Fn(Vec3) -> (f32, Vec3) + Sync> SignedDistance for SdfFn<F> {
    fn distance(&self, p: Vec3) -> f32 {
        (self.0)(p).0
    }
    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        (self.0)(p)
    }
}

/// Closest points on the surface being fitted: what the banded fit needs once the signed
/// distances at the nodes are known (no sign queries).
pub trait ClosestPoint: Sync {
    /// The surface point closest to `p`; the caller knows one lies within `max_distance`, which
    /// a search may use to prune. `None` when there is none.
    fn closest_point(&self, p: Vec3, max_distance: f32) -> Option<Vec3>;
}

/// Adapts a closure `(p, max_distance) -> closest point` to [`ClosestPoint`].
pub struct ClosestFn<F>(pub F);

impl<F: Fn(Vec3, f32) -> Option<Vec3> + Sync> ClosestPoint for ClosestFn<F> {
    fn closest_point(&self, p: Vec3, max_distance: f32) -> Option<Vec3> {
        (self.0)(p, max_distance)
    }
}

/// The closest points of a [`SignedDistance`]: one step back along its gradient.
pub struct SurfaceOf<'a>(pub &'a dyn SignedDistance);

impl ClosestPoint for SurfaceOf<'_> {
    fn closest_point(&self, p: Vec3, _max_distance: f32) -> Option<Vec3> {
        let (d, n) = self.0.distance_gradient(p);
        let c = p - d * n;
        c.is_finite().then_some(c)
    }
}
