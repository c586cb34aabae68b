//! `pgvol_field::fit::SignedDistance`, the distance the fits query: the facade's mesh distance
//! (on the box mesh), the analytic solids and closures. All are exact distances: equal to the
//! closed form up to rounding, 1-Lipschitz, with unit gradients pointing away from the closest
//! surface point.

use pgvol::distances::MeshDistance;
use pgvol::field::analytic::{RotatedBox, Sphere, Torus};
use pgvol::field::fit::{SdfFn, SignedDistance};
use pgvol::glam::Vec3;
use pgvol::sdf::sampling::Extent;
use pgvol::{GridSpec, SdfOptions, Silent};
use proptest::prelude::*;

use crate::properties::{property_tests, Case, Evaluate};
use crate::subjects::{self, box_mesh, Spec, BOX_HI, BOX_LO};
use crate::support::{bits, check, point_in, with_threads, THREADS};

/// Evaluates through [`SignedDistance`] only.
pub struct ViaSdf<S>(S);

impl<S: SignedDistance> Evaluate for ViaSdf<S> {
    fn value(&self, p: Vec3) -> f32 {
        self.0.distance(p)
    }
    fn value_gradient(&self, p: Vec3) -> (f32, Vec3) {
        self.0.distance_gradient(p)
    }
}

fn case<S: SignedDistance>(sdf: S, spec: Spec) -> Case<ViaSdf<S>> {
    Case {
        field: ViaSdf(sdf),
        spec,
    }
}

fn mesh_distance() -> Case<ViaSdf<MeshDistance<'static>>> {
    case(MeshDistance(&box_mesh().1), subjects::box_mesh_spec())
}

fn ball() -> Case<ViaSdf<Sphere>> {
    case(subjects::BALL, subjects::ball_spec())
}

fn slab() -> Case<ViaSdf<RotatedBox>> {
    case(subjects::slab(), subjects::slab_spec())
}

fn ring() -> Case<ViaSdf<Torus>> {
    case(subjects::RING, subjects::ring_spec())
}

fn closure() -> Case<ViaSdf<impl SignedDistance>> {
    case(
        SdfFn(|p| subjects::RING.distance_gradient(p)),
        subjects::ring_spec(),
    )
}

/// The gradient is a unit vector everywhere, on the surface and the medial axis included: the
/// fits step along it by the distance.
fn gradient_is_a_unit_vector<S: SignedDistance>(case: &Case<ViaSdf<S>>) {
    let Case { field, spec } = case;
    check(512, point_in(spec.region), |p| {
        let (_, g) = field.0.distance_gradient(p);
        prop_assert!((g.length() - 1.0).abs() <= 1e-5, "gradient {} at {}", g, p);
        Ok(())
    });
}

/// `p − d ∇d` is a closest surface point: on the surface and `|d|` away, which is how the fits
/// find the surface ([`pgvol::field::fit::SurfaceOf`]).
fn stepping_back_by_the_distance_lands_on_the_surface<S: SignedDistance>(case: &Case<ViaSdf<S>>) {
    let Case { field, spec } = case;
    check(512, point_in(spec.region), |p| {
        let (d, g) = field.0.distance_gradient(p);
        let c = p - d * g;
        let left = (spec.reference)(c);
        // Rounding of coordinates near 1 in the step, and of the reference there.
        prop_assert!(
            left.abs() <= 2e-6,
            "{} from {} (distance {}) is {} off",
            c,
            p,
            d,
            left
        );
        Ok(())
    });
}

macro_rules! signed_distance_tests {
    ($($name:ident => $case:expr;)*) => {
        property_tests! {
            $($name => $case, also gradient_is_a_unit_vector,
                stepping_back_by_the_distance_lands_on_the_surface;)*
        }
    };
}

signed_distance_tests! {
    mesh_distance => mesh_distance();
    sphere => ball();
    rotated_box => slab();
    torus => ring();
    closure => closure();
}

/// The mesh distance's batch call, a sampled grid, gives the pointwise distances at its nodes,
/// whatever the thread count. Bit equality holds across thread counts; against the pointwise
/// query the grid scans compute squared distances in another order (several triangles per
/// lane), which moves some values by an ulp.
#[test]
fn mesh_distance_grid_matches_pointwise_queries_at_every_thread_count() {
    let (mesh, sdf) = box_mesh();
    let pointwise = MeshDistance(sdf);
    let grid = pgvol::Grid::cube_res(BOX_LO, BOX_HI, 24).unwrap();
    let sampled = sdf.sample_grid(&grid, &|_| {});
    for k in 0..grid.dims[2] {
        for j in 0..grid.dims[1] {
            for i in 0..grid.dims[0] {
                let p = grid.point(i, j, k);
                let (got, want) = (sampled[grid.index(i, j, k)], pointwise.distance(p));
                assert!((got - want).abs() <= 1e-6, "{got} against {want} at {p}");
            }
        }
    }
    let bits_of = |v: &[f32]| v.iter().copied().map(bits).collect::<Vec<_>>();
    for threads in THREADS {
        let again = with_threads(threads, || sdf.sample_grid(&grid, &|_| {}));
        assert_eq!(bits_of(&again), bits_of(&sampled), "{threads} threads");
        let facade = with_threads(threads, || {
            let options = SdfOptions {
                grid: GridSpec::Res(24),
                ..SdfOptions::default()
            };
            pgvol::distances::signed_distance(mesh, &options, &Silent).unwrap()
        });
        assert_eq!(facade.grid, grid);
        assert_eq!(
            bits_of(&facade.values),
            bits_of(&sampled),
            "{threads} threads"
        );
    }
}

/// In a band the sampled grid is the dense one where the band is exact (to an ulp: the brick
/// sizes differ, and with them the order of the lane scans), and holds the clamped magnitude
/// with the right sign elsewhere.
#[test]
fn mesh_distance_band_is_exact_within_and_clamped_beyond() {
    let (_, sdf) = box_mesh();
    let grid = pgvol::Grid::cube_res(BOX_LO, BOX_HI, 24).unwrap();
    let dense = sdf.sample_grid(&grid, &|_| {});
    let width = 2.5;
    let clamp = width * grid.spacing;
    let banded = sdf.sample(&grid, Extent::Band(width), &|_| {});
    assert_eq!(banded.clamp, clamp);
    let (mut within, mut beyond) = (0, 0);
    for (&d, &b) in dense.iter().zip(&banded.values) {
        if d.abs() < clamp {
            within += 1;
            assert!((b - d).abs() <= 1e-6, "banded {b}, dense {d}");
        } else {
            beyond += 1;
            assert_eq!(b, clamp.copysign(d), "dense {d}");
        }
    }
    assert!(
        within > 100 && beyond > 100,
        "{within} within, {beyond} beyond"
    );
}
