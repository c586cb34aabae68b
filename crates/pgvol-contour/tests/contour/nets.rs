//! Surface nets: closed oriented manifolds on the surface, and the classic one-vertex-per-cell
//! surface nets of the `fast-surface-nets` crate wherever every cell holds one component.

use std::collections::BTreeSet;

use fast_surface_nets::ndshape::{RuntimeShape, Shape};
use fast_surface_nets::{surface_nets as classic_nets, SurfaceNetsBuffer};
use glam::Vec3;
use pgvol_contour::Field;
use pgvol_core::Mesh;
use proptest::prelude::*;

use crate::dc_features::sampled;
use crate::dual_topology::check_dual_of_mc;
use crate::fields::{sphere, torus};
use crate::grids::{Rng, Samples};
use crate::topology::{check_balanced, check_surface};

/// The crate's surface nets of `s` at `iso` over the whole grid, and the cell of each vertex.
fn classic(s: &Samples, iso: f32) -> (Mesh, Vec<[u32; 3]>) {
    // The crate makes no quads for edges in its last cell layer, so the grid gets one more
    // layer of outside nodes on its upper sides.
    let d = s.dims.map(|d| d as u32 + 1);
    let shape = RuntimeShape::<u32, 3>::new(d);
    let mut shifted = vec![1.0f32; shape.usize()];
    for (idx, v) in s.values.iter().enumerate() {
        let [nx, ny, _] = s.dims;
        let n = [idx % nx, (idx / nx) % ny, idx / (nx * ny)].map(|x| x as u32);
        shifted[shape.linearize(n) as usize] = v - iso;
    }
    let mut out = SurfaceNetsBuffer::default();
    classic_nets(&shifted, &shape, [0; 3], d.map(|x| x - 1), &mut out);
    let positions = out
        .positions
        .iter()
        .map(|&p| s.origin + Vec3::from_array(p) * s.spacing)
        .collect();
    let triangles = out
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    (Mesh::new(positions, triangles), out.surface_points)
}

/// Cell holding each vertex of `mesh` (vertices stay inside their cells, clear of the faces).
fn vertex_cells(s: &Samples, mesh: &Mesh) -> Vec<[u32; 3]> {
    mesh.positions
        .iter()
        .map(|&p| ((p - s.origin) / s.spacing).floor().as_uvec3().to_array())
        .collect()
}

#[test]
fn sphere_is_a_manifold_on_the_surface() {
    let ball = sphere(0.7);
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
fn matches_the_crates_surface_nets_where_each_cell_has_one_component() {
    // Smooth shapes at a resolution where no cell holds two sheets: the same cells get a
    // vertex and every crossed edge the same quad, so only the positions differ.
    let ball = sphere(0.7);
    let ring = torus(0.55, 0.25);
    let cases: [(&str, usize, &dyn Field); 2] = [("sphere", 40, &ball), ("torus", 48, &ring)];
    for (name, n, field) in cases {
        let s = sampled(n, field);
        let ours = s.nets(0.0, field);
        let (theirs, cells) = classic(&s, 0.0);
        check_surface(&ours);
        let ours_cells: BTreeSet<[u32; 3]> = vertex_cells(&s, &ours).into_iter().collect();
        assert_eq!(
            ours_cells.len(),
            ours.positions.len(),
            "{name}: two vertices in a cell"
        );
        let theirs_cells: BTreeSet<[u32; 3]> = cells.into_iter().collect();
        assert_eq!(ours_cells, theirs_cells, "{name}: cells with a vertex");
        assert_eq!(ours.triangles.len(), theirs.triangles.len(), "{name}");
    }
}

#[test]
fn white_noise_is_manifold_where_one_vertex_per_cell_is_not() {
    let mut rng = Rng::new(31);
    let (mut classic_bad, mut split_cells) = (0, 0);
    for _ in 0..10 {
        let s = Samples::padded([20, 20, 20], 1.0, |_| rng.range(-1.0, 1.0));
        check_dual_of_mc(&s, 0.0);
        let ours = s.nets_trilinear(0.0);
        let (theirs, _) = classic(&s, 0.0);
        let stats = check_balanced(&theirs);
        classic_bad += stats.non_manifold_edges + stats.non_manifold_vertices;
        split_cells += ours.positions.len() - theirs.positions.len();
    }
    println!("white noise: {classic_bad} non-manifold places in one vertex per cell, {split_cells} extra vertices here");
    assert!(
        classic_bad > 0,
        "white noise always has cells with two sheets"
    );
    assert!(split_cells > 0);
}

#[test]
fn surface_is_left_open_where_it_reaches_the_grid_border() {
    // A half space: no quad whose cells leave the grid is kept, as in marching cubes.
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
    fn random_fields_with_nan_and_ties_are_closed_manifolds(
        dims in (3usize..12, 3usize..12, 3usize..12),
        values in prop::collection::vec(value(), 1331),
        iso in -0.5f32..0.5,
    ) {
        let mut it = values.into_iter();
        let s = Samples::padded([dims.0, dims.1, dims.2], 1.0, |_| it.next().unwrap());
        check_dual_of_mc(&s, iso);
    }
}
