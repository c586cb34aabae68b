//! Continuous fields that contouring can evaluate between the grid nodes.

use glam::Vec3;
use pgvol_field::CoefficientVolume;
use pgvol_perturb::PerturbationField;

use crate::cubic_eval::bspline3_value_gradient;

/// A scalar field defined everywhere in space, with its gradient.
///
/// The contouring functions take node samples for the topology and ask the field for vertex
/// placement only, so the two should agree at the nodes (the samples are usually this field
/// evaluated there). Negative is inside, as for signed distance.
pub trait Field: Sync {
    /// Field value at `p`.
    fn value(&self, p: Vec3) -> f32;
    /// Field value and gradient at `p`.
    fn value_gradient(&self, p: Vec3) -> (f32, Vec3);
}

impl Field for CoefficientVolume {
    #[inline]
    fn value(&self, p: Vec3) -> f32 {
        CoefficientVolume::value(self, p)
    }

    /// A cubic B-spline takes a dedicated path away from the border, where dual contouring
    /// and surface nets make most of their evaluations.
    #[inline]
    fn value_gradient(&self, p: Vec3) -> (f32, Vec3) {
        bspline3_value_gradient(self, p).unwrap_or_else(|| self.eval(p))
    }
}

/// Any closure returning value and gradient is a field, which suits analytic shapes.
/// The perturbation field as it is: its value is not a distance, but its zero set and its
/// gradient are what vertex placement needs.
impl Field for PerturbationField {
    #[inline]
    fn value(&self, p: Vec3) -> f32 {
        PerturbationField::value(self, p)
    }

    #[inline]
    fn value_gradient(&self, p: Vec3) -> (f32, Vec3) {
        PerturbationField::value_gradient(self, p)
    }
}

impl<F> Field for F
where
    F: Fn(Vec3) -> (f32, Vec3) + Sync,
{
    #[inline]
    fn value(&self, p: Vec3) -> f32 {
        self(p).0
    }

    #[inline]
    fn value_gradient(&self, p: Vec3) -> (f32, Vec3) {
        self(p)
    }
}
