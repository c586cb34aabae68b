//! Topology and geometry summary of a mesh, with edge counting by sorting (no hash maps) so a
//! million triangles take well under a second.

use serde::Serialize;

use super::Mesh;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshStats {
    /// Vertices referenced by at least one triangle.
    pub vertices: usize,
    pub triangles: usize,
    /// Unique undirected edges.
    pub edges: usize,
    /// Edges used by exactly one triangle.
    pub boundary_edges: usize,
    /// Edges used by three or more triangles.
    pub non_manifold_edges: usize,
    /// Every edge used by exactly two triangles (as trimesh's `is_watertight`).
    pub watertight: bool,
    /// Every edge shared by two triangles is traversed once in each direction.
    pub winding_consistent: bool,
    /// V - E + F.
    pub euler_characteristic: i64,
    /// Signed volume by the divergence theorem; positive for outward-facing closed meshes.
    pub volume: f64,
    pub area: f64,
    /// Connected components, where triangles sharing a vertex are connected.
    pub components: usize,
}

impl Mesh {
    pub fn stats(&self) -> MeshStats {
        let n = self.positions.len();

        // Undirected edge key in the high bits, direction (1 if stored min->max) in bit 0.
        let mut edges: Vec<u128> = Vec::with_capacity(3 * self.triangles.len());
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let (lo, hi, forward) = if a <= b { (a, b, 1) } else { (b, a, 0) };
                edges.push((u128::from(lo) << 33) | (u128::from(hi) << 1) | forward);
            }
        }
        edges.sort_unstable();
        let (mut unique, mut boundary, mut non_manifold) = (0, 0, 0);
        let mut winding_consistent = true;
        for run in edges.chunk_by(|a, b| a >> 1 == b >> 1) {
            unique += 1;
            match run.len() {
                1 => boundary += 1,
                2 => winding_consistent &= (run[0] & 1) != (run[1] & 1),
                _ => non_manifold += 1,
            }
        }
        let watertight = !edges.is_empty() && boundary == 0 && non_manifold == 0;

        // Union-find over vertices: a triangle joins its three corners.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        let mut used = vec![false; n];
        let (mut volume, mut area) = (0.0f64, 0.0f64);
        for &[a, b, c] in &self.triangles {
            let (ia, ib, ic) = (a as usize, b as usize, c as usize);
            if ia >= n || ib >= n || ic >= n {
                continue;
            }
            used[ia] = true;
            used[ib] = true;
            used[ic] = true;
            union(&mut parent, a, b);
            union(&mut parent, a, c);
            let [p, q, r] = [ia, ib, ic].map(|i| self.positions[i].as_dvec3());
            volume += p.dot(q.cross(r)) / 6.0;
            area += 0.5 * (q - p).cross(r - p).length();
        }
        let vertices = used.iter().filter(|&&u| u).count();
        let components = (0..n as u32)
            .filter(|&i| used[i as usize] && find(&mut parent, i) == i)
            .count();

        MeshStats {
            vertices,
            triangles: self.triangles.len(),
            edges: unique,
            boundary_edges: boundary,
            non_manifold_edges: non_manifold,
            watertight,
            winding_consistent,
            euler_characteristic: vertices as i64 - unique as i64 + self.triangles.len() as i64,
            volume,
            area,
            components,
        }
    }
}

pub(super) fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        // Path halving keeps trees shallow without recursion.
        let g = parent[parent[i as usize] as usize];
        parent[i as usize] = g;
        i = g;
    }
    i
}

pub(super) fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        // Smaller root wins: deterministic and good enough with path halving.
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        parent[hi as usize] = lo;
    }
}
