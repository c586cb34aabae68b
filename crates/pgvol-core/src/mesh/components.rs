//! Removing the small pieces of a mesh: specks a contouring leaves around noise or thin
//! features, which a printer would fill as separate bodies.

use super::stats::{find, union};
use super::Mesh;

impl Mesh {
    /// Removes the connected pieces (triangles sharing vertices) that enclose less than
    /// `min_volume` (absolute signed volume, so small voids go too), then the vertices no
    /// triangle uses. Returns how many pieces were removed.
    pub fn remove_small_components(&mut self, min_volume: f64) -> usize {
        let n = self.positions.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        for &[a, b, c] in &self.triangles {
            union(&mut parent, a, b);
            union(&mut parent, a, c);
        }
        let mut volume = vec![0.0f64; n];
        let mut has_triangles = vec![false; n];
        for &[a, b, c] in &self.triangles {
            let root = find(&mut parent, a) as usize;
            let [p, q, r] = [a, b, c].map(|i| self.positions[i as usize].as_dvec3());
            volume[root] += p.dot(q.cross(r)) / 6.0;
            has_triangles[root] = true;
        }
        let small: Vec<bool> = (0..n)
            .map(|i| has_triangles[i] && volume[i].abs() < min_volume)
            .collect();
        let removed = small.iter().filter(|&&s| s).count();
        if removed == 0 {
            return 0;
        }
        self.triangles
            .retain(|t| !small[find(&mut parent, t[0]) as usize]);
        self.drop_unused_vertices();
        removed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A closed tetrahedron scaled by `s` and moved by `at`.
    fn tetra(mesh: &mut Mesh, s: f32, at: Vec3) {
        let base = mesh.positions.len() as u32;
        for p in [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z] {
            mesh.positions.push(p * s + at);
        }
        for t in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
            mesh.triangles.push(t.map(|i| i + base));
        }
    }

    #[test]
    fn small_pieces_go_and_large_ones_stay_whole() {
        let mut mesh = Mesh::default();
        tetra(&mut mesh, 1.0, Vec3::ZERO);
        tetra(&mut mesh, 0.1, Vec3::splat(5.0));
        tetra(&mut mesh, 0.2, Vec3::splat(-5.0));
        // Volumes 1/6, 1/6000 and 8/6000.
        assert_eq!(mesh.clone().remove_small_components(0.0), 0);
        let mut m = mesh.clone();
        assert_eq!(m.remove_small_components(0.001), 1);
        assert_eq!((m.triangles.len(), m.positions.len()), (8, 8));
        assert!((m.stats().volume - (1.0 / 6.0 + 8.0 / 6000.0)).abs() < 1e-6);
        assert_eq!(mesh.remove_small_components(0.01), 2);
        assert_eq!(mesh.stats().components, 1);
    }
}
