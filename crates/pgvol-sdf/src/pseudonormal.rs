//! Angle-weighted pseudonormals (Bærentzen & Aanæs 2005): the sign of `(p − c) · n` at the closest
//! point `c`, with `n` the pseudonormal of the feature holding `c`, tells inside from outside
//! exactly for closed, consistently oriented, manifold meshes.

use glam::{Vec3, Vec3A};
use rayon::prelude::*;

use crate::bvh::Bvh;
use crate::triangle::Feature;

/// Per triangle (in leaf order): face normal, the normals of its three edges (from corner n to
/// n + 1) and of its three corners. Kept unpadded: 84 bytes a triangle instead of 112.
#[derive(Clone, Debug)]
pub struct Pseudonormals {
    normals: Vec<[Vec3; 7]>,
}

impl Pseudonormals {
    pub fn new(mesh: &pgvol_mesh::Mesh, bvh: &Bvh) -> Pseudonormals {
        let face = |t: usize| -> Vec3A {
            let [a, b, c] = mesh.triangle(t);
            Vec3A::from((b - a).cross(c - a)).normalize_or_zero()
        };
        let mut vertex = vec![Vec3A::ZERO; mesh.positions.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let n = face(t);
            let p = mesh.triangle(t).map(Vec3A::from);
            for c in 0..3 {
                let (u, v) = (p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]);
                let angle = u.angle_between(v);
                if angle.is_finite() {
                    vertex[tri[c] as usize] += angle * n;
                }
            }
        }
        let edge = edge_normals(mesh, face);
        let normals = bvh
            .tri_ids
            .iter()
            .map(|&t| {
                let tri = mesh.triangles[t as usize];
                let e = |c: usize| Vec3::from(edge[3 * t as usize + c]);
                let v = |c: usize| Vec3::from(vertex[tri[c] as usize]);
                [
                    Vec3::from(face(t as usize)),
                    e(0),
                    e(1),
                    e(2),
                    v(0),
                    v(1),
                    v(2),
                ]
            })
            .collect();
        Pseudonormals { normals }
    }

    /// The (unnormalised) pseudonormal of a feature of the triangle at leaf slot `slot`.
    #[inline]
    pub fn normal(&self, slot: u32, feature: Feature) -> Vec3A {
        let n = &self.normals[slot as usize];
        Vec3A::from(match feature {
            Feature::Face => n[0],
            Feature::Edge(e) => n[1 + e as usize],
            Feature::Vertex(v) => n[4 + v as usize],
        })
    }
}

/// Per half-edge `3 t + c` (triangle `t`, from corner `c` to `c + 1`): the sum of the face
/// normals of every triangle on its edge, added in triangle order. Half-edges are sorted by
/// edge rather than hashed: 16 bytes each against about 70 for a map entry.
fn edge_normals(mesh: &pgvol_mesh::Mesh, face: impl Fn(usize) -> Vec3A + Sync) -> Vec<Vec3A> {
    let mut halves: Vec<(u64, u32)> = mesh
        .triangles
        .iter()
        .enumerate()
        .flat_map(|(t, tri)| {
            (0..3).map(move |c| {
                let (a, b) = (tri[c], tri[(c + 1) % 3]);
                let key = u64::from(a.min(b)) << 32 | u64::from(a.max(b));
                (key, (3 * t + c) as u32)
            })
        })
        .collect();
    halves.par_sort_unstable();
    let mut out = vec![Vec3A::ZERO; halves.len()];
    for run in halves.chunk_by(|x, y| x.0 == y.0) {
        let sum = run
            .iter()
            .fold(Vec3A::ZERO, |s, &(_, h)| s + face(h as usize / 3));
        for &(_, h) in run {
            out[h as usize] = sum;
        }
    }
    out
}
