//! Angle-weighted pseudonormals (Bærentzen & Aanæs 2005): the sign of `(p − c) · n` at the closest
//! point `c`, with `n` the pseudonormal of the feature holding `c`, tells inside from outside
//! exactly for closed, consistently oriented, manifold meshes.

use glam::Vec3A;
use std::collections::HashMap;

use crate::bvh::Bvh;
use crate::triangle::Feature;

/// Per triangle (in leaf order): face normal, the normals of its three edges (from corner n to
/// n + 1) and of its three corners.
#[derive(Clone, Debug)]
pub struct Pseudonormals {
    normals: Vec<[Vec3A; 7]>,
}

impl Pseudonormals {
    pub fn new(mesh: &pgvol_mesh::Mesh, bvh: &Bvh) -> Pseudonormals {
        let face = |t: usize| -> Vec3A {
            let [a, b, c] = mesh.triangle(t);
            Vec3A::from((b - a).cross(c - a)).normalize_or_zero()
        };
        let mut vertex = vec![Vec3A::ZERO; mesh.positions.len()];
        let mut edge: HashMap<(u32, u32), Vec3A> =
            HashMap::with_capacity(mesh.triangles.len() * 3 / 2);
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let n = face(t);
            let p = mesh.triangle(t).map(Vec3A::from);
            for c in 0..3 {
                let (u, v) = (p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]);
                let angle = u.angle_between(v);
                if angle.is_finite() {
                    vertex[tri[c] as usize] += angle * n;
                }
                let (a, b) = (tri[c], tri[(c + 1) % 3]);
                *edge.entry((a.min(b), a.max(b))).or_insert(Vec3A::ZERO) += n;
            }
        }
        let normals = bvh
            .tri_ids
            .iter()
            .map(|&t| {
                let tri = mesh.triangles[t as usize];
                let e = |c: usize| {
                    let (a, b) = (tri[c], tri[(c + 1) % 3]);
                    edge[&(a.min(b), a.max(b))]
                };
                [
                    face(t as usize),
                    e(0),
                    e(1),
                    e(2),
                    vertex[tri[0] as usize],
                    vertex[tri[1] as usize],
                    vertex[tri[2] as usize],
                ]
            })
            .collect();
        Pseudonormals { normals }
    }

    /// The (unnormalised) pseudonormal of a feature of the triangle at leaf slot `slot`.
    #[inline]
    pub fn normal(&self, slot: u32, feature: Feature) -> Vec3A {
        let n = &self.normals[slot as usize];
        match feature {
            Feature::Face => n[0],
            Feature::Edge(e) => n[1 + e as usize],
            Feature::Vertex(v) => n[4 + v as usize],
        }
    }
}
