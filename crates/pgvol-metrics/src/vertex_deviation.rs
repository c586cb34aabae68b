//! Deviation of a mesh's vertices from another surface (the perturbation paper's first two
//! measures): the distance from each vertex of A to B, and the angle between A's vertex normal
//! and B's normal at the closest point, interpolated from B's vertex normals (so a mesh
//! against itself deviates by zero, corners included).

use glam::Vec3;
use pgvol_mesh::Mesh;
use pgvol_sdf::Bvh;
use rayon::prelude::*;
use serde::Serialize;

/// Distances and normal angles at the vertices of A against B.
#[derive(Clone, Debug, Serialize)]
pub struct VertexDeviation {
    pub vertices: usize,
    pub mean: f64,
    pub max: f64,
    /// Angle between the vertex normal of A (area-weighted) and B's normal at the vertex's
    /// closest point (B's vertex normals interpolated barycentrically), in degrees.
    pub normal_mean_deg: f64,
    pub normal_max_deg: f64,
}

/// Measures the vertices of `a` against `b` through `b`'s BVH.
pub fn vertex_deviation(a: &Mesh, b: &Mesh, bvh_b: &Bvh) -> VertexDeviation {
    let normals = pgvol_mesh::vertex_normals(a);
    let normals_b = pgvol_mesh::vertex_normals(b);
    let pairs: Vec<(f64, f64)> = a
        .positions
        .par_iter()
        .zip(&normals)
        .map(|(&p, &n)| {
            let c = bvh_b
                .closest(p, f32::INFINITY)
                .expect("target mesh has triangles");
            let t = b.triangles[c.triangle as usize];
            let w = barycentric(c.point, b.triangle(c.triangle as usize));
            let m = (normals_b[t[0] as usize] * w[0]
                + normals_b[t[1] as usize] * w[1]
                + normals_b[t[2] as usize] * w[2])
                .normalize_or_zero();
            let cos = n.dot(m).clamp(-1.0, 1.0) as f64;
            ((c.distance_squared as f64).sqrt(), cos.acos().to_degrees())
        })
        .collect();
    let k = pairs.len().max(1) as f64;
    VertexDeviation {
        vertices: pairs.len(),
        mean: pairs.iter().map(|p| p.0).sum::<f64>() / k,
        max: pairs.iter().map(|p| p.0).fold(0.0, f64::max),
        normal_mean_deg: pairs.iter().map(|p| p.1).sum::<f64>() / k,
        normal_max_deg: pairs.iter().map(|p| p.1).fold(0.0, f64::max),
    }
}

/// Barycentric weights of `p` (a point of the triangle) in `[a, b, c]`; a degenerate triangle
/// weighs its corners equally.
fn barycentric(p: Vec3, [a, b, c]: [Vec3; 3]) -> [f32; 3] {
    let (e0, e1, d) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let (d20, d21) = (d.dot(e0), d.dot(e1));
    let den = d00 * d11 - d01 * d01;
    if den <= 0.0 || !den.is_finite() {
        return [1.0 / 3.0; 3];
    }
    let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}
