//! Smooth shapes with known topology, size and position.

use glam::Vec3;
use pgvol_contour::{marching_cubes, marching_cubes_with};

use crate::grids::Samples;
use crate::topology::check_surface;

const R: f32 = 0.7;

fn sphere(n: usize) -> Samples {
    let spacing = 2.0 / (n - 1) as f32;
    Samples::from_fn([n; 3], Vec3::splat(-1.0), spacing, |p| p.length() - R)
}

/// Largest distance of a linearly interpolated crossing from a sphere of radius `r`: along an
/// edge of length `h` the distance function is convex with second derivative at most
/// `1 / (r - h)`, so the chord's root lies within `h^2 / (8 (r - h))` of the surface; the end
/// margin moves a vertex by up to 1e-4 h, and f32 rounding adds a little.
fn sphere_error_bound(r: f32, h: f32) -> f32 {
    h * h / (8.0 * (r - h)) + 1e-4 * h + 4.0 * f32::EPSILON
}

#[test]
fn sphere_is_a_closed_genus_zero_surface_of_the_right_size() {
    let s = sphere(64);
    let mesh = s.contour(0.0);
    let closed = check_surface(&mesh);
    assert_eq!(closed.euler, 2);
    assert_eq!(closed.component_volumes.len(), 1);
    let exact = 4.0 / 3.0 * std::f64::consts::PI * f64::from(R).powi(3);
    let rel = (closed.volume - exact).abs() / exact;
    assert!(rel < 0.01, "volume {} vs {exact} ({rel})", closed.volume);

    let bound = sphere_error_bound(R, s.spacing);
    let worst = mesh
        .positions
        .iter()
        .map(|p| (p.length() - R).abs())
        .fold(0.0, f32::max);
    assert!(bound < 0.01 * s.spacing, "bound {bound} is not meaningful");
    assert!(
        worst <= bound,
        "vertex {worst} from the sphere, bound {bound}"
    );
}

#[test]
fn torus_has_euler_characteristic_zero() {
    let (major, minor) = (0.55f32, 0.25f32);
    let s = Samples::from_fn([64; 3], Vec3::splat(-1.0), 2.0 / 63.0, |p| {
        Vec3::new(p.truncate().length() - major, p.z, 0.0).length() - minor
    });
    let closed = check_surface(&s.contour(0.0));
    assert_eq!(closed.euler, 0);
    assert_eq!(closed.component_volumes.len(), 1);
    let exact = 2.0 * std::f64::consts::PI.powi(2) * f64::from(major * minor * minor);
    assert!((closed.volume - exact).abs() / exact < 0.01);
}

#[test]
fn nonzero_iso_contours_the_offset_surface() {
    let s = sphere(48);
    let mesh = s.contour(0.1);
    let closed = check_surface(&mesh);
    assert_eq!(closed.euler, 2);
    let bound = sphere_error_bound(R + 0.1, s.spacing);
    for p in &mesh.positions {
        assert!((p.length() - (R + 0.1)).abs() <= bound);
    }
}

#[test]
fn refinement_callback_places_vertices_on_the_true_surface() {
    let s = sphere(40);
    let f = |p: Vec3| p.length() - R;
    let bisect = |mut a: Vec3, va: f32, mut b: Vec3, _vb: f32| {
        let a_inside = va < 0.0;
        for _ in 0..40 {
            let m = (a + b) / 2.0;
            if (f(m) < 0.0) == a_inside {
                a = m;
            } else {
                b = m;
            }
        }
        (a + b) / 2.0
    };
    let mesh = marching_cubes_with(&s.values, s.dims, s.origin, s.spacing, 0.0, &bisect);
    let closed = check_surface(&mesh);
    assert_eq!(closed.euler, 2);
    let worst = mesh
        .positions
        .iter()
        .map(|p| (p.length() - R).abs())
        .fold(0.0, f32::max);
    assert!(worst < 1e-5, "refined vertex {worst} from the sphere");

    // Same vertex count and connectivity as linear placement: refinement only moves vertices.
    let linear = s.contour(0.0);
    assert_eq!(mesh.triangles, linear.triangles);
}

#[test]
fn wild_refinement_results_still_give_a_valid_mesh() {
    let s = sphere(24);
    let wild = |a: Vec3, _: f32, b: Vec3, _: f32| {
        if a.x > 0.0 {
            Vec3::NAN
        } else if a.y > 0.0 {
            a
        } else {
            b * 100.0
        }
    };
    let mesh = marching_cubes_with(&s.values, s.dims, s.origin, s.spacing, 0.0, &wild);
    let closed = check_surface(&mesh);
    assert_eq!(closed.euler, 2);
}

#[test]
fn surface_touching_the_border_is_open_but_oriented() {
    // A slab crossing the whole grid: its surface is cut off at the grid sides.
    let s = Samples::from_fn([8, 8, 8], Vec3::ZERO, 1.0, |p| (p.z - 3.5).abs() - 1.2);
    let mesh = s.contour(0.0);
    let mut directed = std::collections::HashSet::new();
    for t in &mesh.triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            assert!(directed.insert((a, b)), "edge {a}->{b} used twice");
        }
    }
    let border = directed
        .iter()
        .filter(|&&(a, b)| !directed.contains(&(b, a)))
        .count();
    assert!(border > 0, "expected an open surface");
}

#[test]
fn tiny_and_empty_grids() {
    assert!(marching_cubes(&[], [0, 0, 0], Vec3::ZERO, 1.0, 0.0)
        .triangles
        .is_empty());
    assert!(marching_cubes(&[-1.0; 4], [4, 1, 1], Vec3::ZERO, 1.0, 0.0)
        .triangles
        .is_empty());
    let all_inside = Samples::padded([5, 5, 5], -1.0, |_| -1.0);
    assert!(all_inside.contour(0.0).triangles.is_empty());
}

#[test]
#[should_panic(expected = "values do not match")]
fn mismatched_dims_panic() {
    marching_cubes(&[0.0; 7], [2, 2, 2], Vec3::ZERO, 1.0, 0.0);
}

#[test]
fn a_256_sphere_is_one_closed_surface() {
    let mesh = sphere(256).contour(0.0);
    let closed = check_surface(&mesh);
    assert_eq!(closed.euler, 2);
}
