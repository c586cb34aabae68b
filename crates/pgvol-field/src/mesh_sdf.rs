//! The mesh signed distance of `pgvol-sdf` as a [`SignedDistance`]: the gradient is the unit
//! direction from the closest surface point, signed like the distance.

use glam::Vec3;
use pgvol_sdf::MeshSdf;

use crate::fit::SignedDistance;

impl SignedDistance for MeshSdf {
    fn distance(&self, p: Vec3) -> f32 {
        self.signed_distance(p)
    }

    fn distance_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let (d, slot) = self.signed_distance_with_hint(p, None);
        let Some(slot) = slot else {
            return (d, Vec3::ZERO);
        };
        let c = self.bvh().closest_on_slot(p, slot);
        let v = p - c.point;
        let l = v.length();
        if l > 1e-6 * (1.0 + p.abs().max_element()) {
            return (d, v / l * d.signum());
        }
        // On the surface the direction is undefined: take central differences at a tiny step.
        let e = 1e-4 * (1.0 + p.abs().max_element());
        let g = Vec3::new(
            self.signed_distance(p + Vec3::X * e) - self.signed_distance(p - Vec3::X * e),
            self.signed_distance(p + Vec3::Y * e) - self.signed_distance(p - Vec3::Y * e),
            self.signed_distance(p + Vec3::Z * e) - self.signed_distance(p - Vec3::Z * e),
        );
        (d, g.normalize_or_zero())
    }
}
