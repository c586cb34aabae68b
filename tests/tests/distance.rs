//! The BVH closest-point search against an exhaustive search, on every shared mesh.

use glam::{Vec3, Vec3A};
use pgvol::sdf::{triangle::closest_point_and_distance, Bvh, MeshSdf, SignMode};
use pgvol_tests::{load_shared, margin_cube, random_points, SHARED_MESHES};
use rayon::prelude::*;

/// Squared distance to the nearest triangle by trying all of them, computed exactly as the BVH
/// computes it so that the two must agree to the bit.
fn brute_force_d2(mesh: &pgvol::mesh::Mesh, p: Vec3) -> f32 {
    let q = Vec3A::from(p);
    (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            closest_point_and_distance(q, a.into(), b.into(), c.into()).2
        })
        .fold(f32::INFINITY, f32::min)
}

#[test]
fn bvh_and_sdf_distances_equal_brute_force_on_every_shared_mesh() {
    for (m, name) in SHARED_MESHES.iter().enumerate() {
        let mesh = load_shared(name);
        let bvh = Bvh::build(&mesh);
        let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
        let (lo, hi) = margin_cube(&mesh);
        let mut points = random_points(lo, hi, 300, 100 + m as u64);
        // Points just off the surface, where near-ties between triangles are common.
        let diag = (hi - lo).length();
        let samples = pgvol::metrics::sample_surface(&mesh, 100, 200 + m as u64).unwrap();
        points.extend(
            samples
                .iter()
                .enumerate()
                .map(|(i, s)| s.point + s.normal * (diag * 1e-3 * (i as f32 / 50.0 - 1.0))),
        );

        let failures: Vec<String> = points
            .par_iter()
            .filter_map(|&p| {
                let c = bvh.closest(p, f32::INFINITY).expect("mesh has triangles");
                let d2 = brute_force_d2(&mesh, p);
                let d = pgvol::metrics::brute_force_distance(&mesh, p);
                let s = sdf.signed_distance(p);
                // The reported triangle and point must be consistent with the distance.
                let [a, b, t] = mesh.triangle(c.triangle as usize);
                let (x, _, _) = closest_point_and_distance(p.into(), a.into(), b.into(), t.into());
                let ok = c.distance_squared == d2
                    && c.distance_squared.sqrt() == d
                    && s.abs() == d
                    && Vec3::from(x) == c.point;
                (!ok).then(|| {
                    format!(
                        "{p}: bvh d2 {} vs brute {d2}; brute dist {d}, sdf {s}, point {} vs {}",
                        c.distance_squared,
                        c.point,
                        Vec3::from(x)
                    )
                })
            })
            .collect();
        assert!(
            failures.is_empty(),
            "{name}: {} of {} points disagree, first: {}",
            failures.len(),
            points.len(),
            failures[0]
        );
    }
}
