//! `pgvol_field::fit::ClosestPoint`, the surface the banded fits project onto: the closure the
//! encoder builds over the mesh's hierarchy, and the surface of a signed distance. A closest
//! point lies on the surface, exactly as far from the query as the surface is.

use pgvol::field::fit::{ClosestFn, ClosestPoint, SurfaceOf};
use pgvol::glam::Vec3;
use proptest::prelude::*;

use crate::subjects::{self, box_mesh, Spec};
use crate::support::{check, point_in};

/// The closest point is found within `|d| + slack` and is on the surface, `|d|` from the query.
fn closest_points_are_on_the_surface_and_nearest(surface: &dyn ClosestPoint, spec: &Spec) {
    check(512, point_in(spec.region), |p| {
        let d = (spec.reference)(p);
        let reach = d.abs() + 1e-3;
        let c = surface.closest_point(p, reach);
        prop_assert!(c.is_some(), "no closest point within {} of {}", reach, p);
        let c = c.unwrap();
        // Rounding of coordinates near 1.
        prop_assert!(
            (spec.reference)(c).abs() <= 2e-6,
            "{} is off the surface",
            c
        );
        prop_assert!(
            (p.distance(c) - d.abs()).abs() <= 2e-6,
            "{} is {} from {}, the surface {}",
            c,
            p.distance(c),
            p,
            d
        );
        Ok(())
    });
}

/// What the encoder's banded fit uses: the hierarchy's closest point, pruned by the reach.
#[test]
fn closure_over_the_mesh_hierarchy() {
    let (_, sdf) = box_mesh();
    let surface =
        ClosestFn(|p: Vec3, reach: f32| sdf.bvh().closest(p, reach * reach).map(|c| c.point));
    closest_points_are_on_the_surface_and_nearest(&surface, &subjects::box_mesh_spec());
}

#[test]
fn surface_of_the_mesh_distance() {
    let distance = pgvol::distances::MeshDistance(&box_mesh().1);
    closest_points_are_on_the_surface_and_nearest(
        &SurfaceOf(&distance),
        &subjects::box_mesh_spec(),
    );
}

#[test]
fn surface_of_an_analytic_torus() {
    closest_points_are_on_the_surface_and_nearest(
        &SurfaceOf(&subjects::RING),
        &subjects::ring_spec(),
    );
}
