//! `pgvol_contour::Field`, the field contouring places vertices with: the coefficient volume in
//! every basis (encoded from the sphere mesh), the facade's exact mesh field (on the box mesh)
//! and closures (on an analytic rotated box).
//!
//! Bounds of the encoded volumes are the largest seen over 20 000 points within two spacings of
//! the surface at 32³, with a margin of 20 % or more: accuracy in spacings, then the Lipschitz
//! bound (over the largest gradient norm). Exact fields are held to the distance up to rounding and
//! to a Lipschitz bound of 1. The perturbation field (built from the bumpy sphere mesh) is held
//! to the bumpy sphere's distance near its surface and to its own measured gradient bound.

use pgvol::contour::Field;
use pgvol::distances::MeshField;
use pgvol::field::fit::SignedDistance;
use pgvol::glam::Vec3;
use pgvol::perturbation::PerturbationField;
use pgvol::{Basis, CoefficientVolume};

use crate::properties::{property_tests, Case, Evaluate};
use crate::subjects::{self, box_mesh, encoded, encoded_spec, Fitted};

/// Evaluates through [`Field`] only.
pub struct ViaField<F>(F);

impl<F: Field> Evaluate for ViaField<F> {
    fn value(&self, p: Vec3) -> f32 {
        Field::value(&self.0, p)
    }
    fn value_gradient(&self, p: Vec3) -> (f32, Vec3) {
        Field::value_gradient(&self.0, p)
    }
}

fn volume(basis: Basis, accuracy: f32, lipschitz: f32) -> Case<ViaField<CoefficientVolume>> {
    let volume = encoded(basis);
    let spec = encoded_spec(
        &volume,
        Fitted {
            accuracy,
            lipschitz,
        },
    );
    Case {
        field: ViaField(volume),
        spec,
    }
}

fn mesh_field() -> Case<ViaField<MeshField<'static>>> {
    let (mesh, sdf) = box_mesh();
    Case {
        field: ViaField(MeshField::new(mesh, sdf, 0.05)),
        spec: subjects::box_mesh_spec(),
    }
}

fn perturbation() -> Case<ViaField<PerturbationField>> {
    let (field, spec) = subjects::perturbation();
    Case {
        field: ViaField(field),
        spec,
    }
}

fn closure() -> Case<ViaField<impl Fn(Vec3) -> (f32, Vec3) + Sync>> {
    let slab = subjects::slab();
    Case {
        field: ViaField(move |p| slab.distance_gradient(p)),
        spec: subjects::slab_spec(),
    }
}

// Measured accuracy (spacings) and largest gradient norm: bspline3 0.057, 1.26; bspline2
// 0.054, 1.17; trilinear 0.099, 1.09; pg-n3-r1.5 0.12, 1.34; pg-n4-r1.5 0.41, 1.70.
property_tests! {
    bspline3_volume => volume(Basis::Bspline3, 0.1, 1.5);
    bspline2_volume => volume(Basis::Bspline2, 0.1, 1.4);
    trilinear_volume => volume(Basis::Trilinear, 0.15, 1.3);
    pg_n3_r1_5_volume => volume(Basis::Pg { n: 3, r: 1.5 }, 0.2, 1.6);
    pg_n4_r1_5_volume => volume(Basis::Pg { n: 4, r: 1.5 }, 0.6, 2.0);
    exact_mesh_field => mesh_field();
    closure => closure();
    perturbation_field => perturbation();
}
