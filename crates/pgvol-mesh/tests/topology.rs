//! Statistics, cleaning and normals on small meshes whose answers are known by hand.

mod common;

use glam::Vec3;
use pgvol_mesh::{face_normal, vertex_normals, Mesh};

use common::unit_cube;

#[test]
fn closed_cube() {
    let s = unit_cube().stats();
    assert_eq!((s.vertices, s.triangles, s.edges), (8, 12, 18));
    assert_eq!((s.boundary_edges, s.non_manifold_edges), (0, 0));
    assert!(s.watertight && s.winding_consistent);
    assert_eq!(s.euler_characteristic, 2);
    assert_eq!(s.components, 1);
    assert!((s.volume - 1.0).abs() < 1e-12, "{}", s.volume);
    assert!((s.area - 6.0).abs() < 1e-12, "{}", s.area);
}

#[test]
fn open_box_inverted_and_disjoint() {
    let mut open = unit_cube();
    open.triangles.drain(0..2); // remove the z = 0 face
    let s = open.stats();
    assert_eq!(s.boundary_edges, 4);
    assert!(!s.watertight);
    assert!(s.winding_consistent);
    assert_eq!(s.euler_characteristic, 1);
    assert!((s.area - 5.0).abs() < 1e-12);

    let mut inverted = unit_cube();
    for t in &mut inverted.triangles {
        t.swap(1, 2);
    }
    let s = inverted.stats();
    assert!(s.watertight && s.winding_consistent);
    assert!((s.volume + 1.0).abs() < 1e-12);

    let mut flipped_one = unit_cube();
    flipped_one.triangles[5].swap(1, 2);
    let s = flipped_one.stats();
    assert!(s.watertight && !s.winding_consistent);

    // Two cubes side by side: two components, Euler characteristic 4.
    let mut two = unit_cube();
    let off = two.positions.len() as u32;
    let moved: Vec<Vec3> = two
        .positions
        .iter()
        .map(|p| *p + Vec3::splat(3.0))
        .collect();
    two.positions.extend(moved);
    let extra: Vec<[u32; 3]> = two.triangles.iter().map(|t| t.map(|i| i + off)).collect();
    two.triangles.extend(extra);
    let s = two.stats();
    assert_eq!((s.components, s.euler_characteristic), (2, 4));
    assert!((s.volume - 2.0).abs() < 1e-12);
}

#[test]
fn non_manifold_fan_and_unreferenced_vertices() {
    // Three triangles on edge 0-1, plus an unused vertex.
    let m = Mesh::new(
        vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::Y,
            Vec3::splat(9.0),
        ],
        vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]],
    );
    let s = m.stats();
    assert_eq!(s.non_manifold_edges, 1);
    assert_eq!(s.boundary_edges, 6);
    assert_eq!(s.vertices, 5);
    assert!(!s.watertight);
}

#[test]
fn weld_exact_and_with_tolerance() {
    // Two triangles sharing an edge, written as soup with slightly jittered copies and -0.0.
    let soup = Mesh::new(
        vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::new(1.0 + 1e-6, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-0.0, 1.0, -0.0),
        ],
        vec![[0, 1, 2], [3, 4, 5]],
    );
    let mut exact = soup.clone();
    assert_eq!(exact.weld(0.0), 1); // only -0.0 == 0.0 for vertex 5
    assert_eq!(exact.positions.len(), 5);
    assert_eq!(exact.triangles, vec![[0, 1, 2], [3, 4, 2]]);

    let mut loose = soup.clone();
    assert_eq!(loose.weld(1e-5), 2);
    assert_eq!(loose.positions.len(), 4);
    assert_eq!(loose.triangles, vec![[0, 1, 2], [1, 3, 2]]);
    let s = loose.stats();
    assert_eq!((s.edges, s.boundary_edges, s.components), (5, 4, 1));
    assert!(s.winding_consistent);

    // A tolerance smaller than the jitter merges nothing more than exact welding.
    let mut tight = soup;
    assert_eq!(tight.weld(1e-8), 1);
}

#[test]
fn degenerate_and_unused_removal() {
    let mut m = unit_cube();
    m.positions.push(Vec3::new(2.0, 0.0, 0.0)); // collinear with 0 and 1
    m.positions.push(Vec3::splat(7.0)); // never used
    m.triangles.push([0, 1, 8]); // zero area
    m.triangles.push([3, 3, 4]); // repeated index
                                 // Tiny but real: must survive (f32 cross product would underflow to zero).
    m.positions.push(Vec3::new(0.0, 1e-30, 0.0));
    m.positions.push(Vec3::new(1e-30, 0.0, 0.0));
    m.triangles.push([0, 11, 10]);
    assert_eq!(m.drop_degenerate(), 2);
    assert_eq!(m.triangles.len(), 13);
    assert_eq!(m.drop_unused_vertices(), 2);
    assert_eq!(m.positions.len(), 10);
    assert_eq!(m.triangles[12], [0, 9, 8]);
    assert_eq!(m.triangle(12)[1], Vec3::new(1e-30, 0.0, 0.0));
}

#[test]
fn normals_are_unit_and_symmetric() {
    let cube = unit_cube();
    let normals = vertex_normals(&cube);
    for (p, n) in cube.positions.iter().zip(&normals) {
        // Angle weighting makes each corner normal the exact diagonal, whatever the split.
        let expect = (*p * 2.0 - Vec3::ONE).normalize();
        assert!((*n - expect).length() < 1e-6, "{p} -> {n}");
    }
    assert_eq!(face_normal(cube.triangle(0)), -Vec3::Z);
    assert_eq!(
        face_normal([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]),
        Vec3::ZERO
    );

    // Unused, degenerate-only, cancelling and tiny cases all still get unit normals.
    let m = Mesh::new(
        vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::splat(5.0),         // unused
            Vec3::new(2.0, 0.0, 0.0), // only in a degenerate triangle
            Vec3::new(0.0, 1e-30, 0.0),
            Vec3::new(1e-30, 0.0, 0.0),
        ],
        vec![[0, 1, 2], [0, 2, 1], [0, 1, 4], [0, 6, 5]],
    );
    let n = vertex_normals(&m);
    for v in &n {
        assert!((v.length() - 1.0).abs() < 1e-6, "{v}");
        assert!(v.is_finite());
    }
    assert_eq!(n[3], Vec3::Z);
    // Vertices 1 and 2 sit in two opposite faces: the sum cancels, a face normal is used.
    assert_eq!(n[1].abs(), Vec3::Z);
    assert_eq!(n[5], Vec3::Z);
}
