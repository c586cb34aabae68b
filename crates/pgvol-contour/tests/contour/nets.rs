//! Surface nets: closed and oriented, welded across chunks, on the surface; manifold except at
//! ambiguous faces.

use glam::Vec3;
use proptest::prelude::*;

use crate::dc_features::sampled;
use crate::fields::{sphere, torus};
use crate::grids::{Rng, Samples};
use crate::topology::{check_balanced, check_surface, Balanced};

/// Asserts the surface nets guarantees and returns the non-manifold counts.
fn check_nets(s: &Samples, iso: f32) -> Balanced {
    let mesh = s.nets_trilinear(iso);
    let stats = check_balanced(&mesh);
    assert!(
        stats.max_uses <= 4,
        "an edge has {} triangles",
        stats.max_uses
    );
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        assert!(
            (b - a).cross(c - a).length() > 0.0,
            "triangle {t} has zero area"
        );
    }
    let mut used = vec![false; mesh.positions.len()];
    mesh.triangles
        .iter()
        .flatten()
        .for_each(|&v| used[v as usize] = true);
    assert!(used.iter().all(|&u| u), "unused vertex");
    stats
}

#[test]
fn sphere_spanning_many_chunks_is_a_welded_manifold_on_the_surface() {
    let ball = sphere(0.7);
    // 80 nodes: 3 chunks per axis, so the surface crosses chunk seams everywhere.
    let s = sampled(80, &ball);
    let mesh = s.nets(0.0, &ball);
    let closed = check_surface(&mesh);
    assert_eq!(closed.euler, 2);
    assert_eq!(closed.component_volumes.len(), 1);
    // Newton steps run along the gradient and stop at the cell's walls, so a vertex whose cell
    // only grazes the surface can end slightly off it; all others land on it.
    let mut errors: Vec<f32> = mesh
        .positions
        .iter()
        .map(|p| (p.length() - 0.7).abs())
        .collect();
    errors.sort_by(f32::total_cmp);
    let (p99, worst) = (errors[errors.len() * 99 / 100], errors[errors.len() - 1]);
    println!(
        "surface nets sphere: 99th percentile {p99}, worst {worst}, spacing {}",
        s.spacing
    );
    assert!(p99 < 1e-4 * s.spacing, "99% of vertices within {p99}");
    assert!(worst < 0.01 * s.spacing, "vertex {worst} from the sphere");
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.7f64.powi(3);
    assert!((closed.volume - exact).abs() / exact < 0.01);
}

#[test]
fn torus_is_a_manifold_of_genus_one() {
    let ring = torus(0.55, 0.25);
    let s = sampled(70, &ring);
    let closed = check_surface(&s.nets(0.0, &ring));
    assert_eq!(closed.euler, 0);
    assert_eq!(closed.component_volumes.len(), 1);
}

#[test]
fn noisy_fields_are_closed_and_oriented_but_not_always_manifold() {
    let mut rng = Rng::new(31);
    let (mut edges, mut vertices, mut triangles) = (0, 0, 0);
    for _ in 0..10 {
        let s = Samples::padded([20, 20, 20], 1.0, |_| rng.range(-1.0, 1.0));
        let stats = check_nets(&s, 0.0);
        edges += stats.non_manifold_edges;
        vertices += stats.non_manifold_vertices;
        triangles += s.nets_trilinear(0.0).triangles.len();
    }
    println!("white noise: {edges} non-manifold edges, {vertices} non-manifold vertices in {triangles} triangles");
    assert!(edges > 0, "white noise always has ambiguous faces");
}

#[test]
fn surface_is_left_open_where_it_reaches_the_grid_border() {
    // A half space: surface nets keep no quad whose cells leave the grid, like marching cubes.
    let s = Samples::from_fn([12, 12, 12], Vec3::ZERO, 1.0, |p| p.x - 5.5);
    let mesh = s.nets(0.0, &|p: Vec3| (p.x - 5.5, Vec3::X));
    assert_eq!(mesh.triangles.len(), 2 * 10 * 10);
    assert!(mesh.positions.iter().all(|p| (p.x - 5.5).abs() < 1e-5));
    let n: Vec3 = (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            (b - a).cross(c - a)
        })
        .sum();
    assert!(n.x > 0.0, "faces point towards increasing values");
}

fn value() -> impl Strategy<Value = f32> {
    prop_oneof![
        8 => -1.0f32..1.0,
        1 => Just(0.0f32),
        1 => Just(f32::NAN),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_fields_are_closed_and_oriented(
        dims in (3usize..12, 3usize..12, 3usize..12),
        values in prop::collection::vec(value(), 1331),
        iso in -0.5f32..0.5,
    ) {
        let mut it = values.into_iter();
        let s = Samples::padded([dims.0, dims.1, dims.2], 1.0, |_| it.next().unwrap());
        check_nets(&s, iso);
    }
}
