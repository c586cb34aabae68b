//! Removing the small pieces of a mesh: specks a contouring leaves around noise or thin
//! features, which a printer would fill as separate bodies.

use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

use rayon::prelude::*;

use super::Mesh;

/// Triangles per chunk whose piece volumes are summed together.
const VOLUME_CHUNK: usize = 1 << 16;

impl Mesh {
    /// Removes the connected pieces (triangles sharing vertices) that enclose less than
    /// `min_volume` (absolute signed volume, so small voids go too), then the vertices no
    /// triangle uses. Returns how many pieces were removed.
    pub fn remove_small_components(&mut self, min_volume: f64) -> usize {
        let n = self.positions.len();
        let roots = piece_roots(n, &self.triangles);
        // Each piece's volume: every chunk of triangles sums its runs of one piece, and the
        // chunks' sums are added in chunk order, so the floats do not depend on the threads.
        let partial: Vec<Vec<(u32, f64)>> = self
            .triangles
            .par_chunks(VOLUME_CHUNK)
            .map(|chunk| {
                let mut sums: Vec<(u32, f64)> = Vec::new();
                for t in chunk {
                    let root = roots[t[0] as usize];
                    let [p, q, r] = t.map(|i| self.positions[i as usize].as_dvec3());
                    let term = p.dot(q.cross(r)) / 6.0;
                    match sums.last_mut() {
                        Some((last, sum)) if *last == root => *sum += term,
                        _ => sums.push((root, term)),
                    }
                }
                sums
            })
            .collect();
        let mut volume = vec![0.0f64; n];
        let mut has_triangles = vec![false; n];
        for (root, sum) in partial.into_iter().flatten() {
            volume[root as usize] += sum;
            has_triangles[root as usize] = true;
        }
        let small: Vec<bool> = (0..n)
            .map(|i| has_triangles[i] && volume[i].abs() < min_volume)
            .collect();
        let removed = small.iter().filter(|&&s| s).count();
        if removed == 0 {
            return 0;
        }
        self.triangles
            .retain(|t| !small[roots[t[0] as usize] as usize]);
        self.drop_unused_vertices();
        removed
    }
}

/// Per vertex of `n`, the smallest vertex index of its piece (vertices joined by `triangles`).
/// The pieces are joined in parallel: a root is linked under a smaller one by a
/// compare-and-swap, so every link points to a smaller index, and each piece ends with its
/// smallest vertex as its root, as it would joined one triangle at a time.
fn piece_roots(n: usize, triangles: &[[u32; 3]]) -> Vec<u32> {
    let parent: Vec<AtomicU32> = (0..n as u32).map(AtomicU32::new).collect();
    triangles.par_iter().for_each(|&[a, b, c]| {
        join(&parent, a, b);
        join(&parent, a, c);
    });
    (0..n as u32)
        .into_par_iter()
        .map(|i| root(&parent, i))
        .collect()
}

/// The root of `i`, halving its path: a vertex that is not a root stays one, and its parent only
/// ever moves to an ancestor, so racing halvings and links keep every piece a tree.
fn root(parent: &[AtomicU32], mut i: u32) -> u32 {
    loop {
        let p = parent[i as usize].load(Relaxed);
        if p == i {
            return i;
        }
        let g = parent[p as usize].load(Relaxed);
        if g != p {
            parent[i as usize].store(g, Relaxed);
        }
        i = g;
    }
}

/// Joins the pieces of `a` and `b`, the larger root linked under the smaller.
fn join(parent: &[AtomicU32], a: u32, b: u32) {
    let (mut a, mut b) = (a, b);
    loop {
        let (ra, rb) = (root(parent, a), root(parent, b));
        if ra == rb {
            return;
        }
        let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
        // Only a root is linked; another thread may have linked `hi` first, then try again
        // from the roots found so far.
        if parent[hi as usize]
            .compare_exchange(hi, lo, Relaxed, Relaxed)
            .is_ok()
        {
            return;
        }
        (a, b) = (ra, rb);
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

    /// The parallel roots are each piece's smallest vertex, as a breadth-first labelling finds
    /// them, on meshes of many pieces joined in random order.
    #[test]
    fn pieces_have_their_smallest_vertex_as_root() {
        let mut x = 7u64;
        let mut next = |m: u64| {
            x = x
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (x >> 33) % m
        };
        for (n, count) in [(50, 20), (5_000, 3_000), (200_000, 150_000)] {
            let triangles: Vec<[u32; 3]> = (0..count)
                .map(|_| {
                    // Nearby vertices mostly, so pieces of many sizes form.
                    let a = next(n as u64);
                    [a, (a + next(9)) % n as u64, (a + next(40)) % n as u64].map(|v| v as u32)
                })
                .collect();
            let mut neighbours = vec![Vec::new(); n];
            for &[a, b, c] in &triangles {
                for (p, q) in [(a, b), (b, c), (a, c)] {
                    neighbours[p as usize].push(q);
                    neighbours[q as usize].push(p);
                }
            }
            let mut want = vec![u32::MAX; n];
            for s in 0..n {
                if want[s] != u32::MAX {
                    continue;
                }
                want[s] = s as u32;
                let mut queue = vec![s as u32];
                while let Some(v) = queue.pop() {
                    for &w in &neighbours[v as usize] {
                        if want[w as usize] == u32::MAX {
                            want[w as usize] = s as u32;
                            queue.push(w);
                        }
                    }
                }
            }
            let got = piece_roots(n, &triangles);
            assert_eq!(got, want, "{n} vertices");
            let pieces = want
                .iter()
                .enumerate()
                .filter(|(i, &r)| r == *i as u32)
                .count();
            assert!(pieces > 1 && pieces < n, "{pieces} pieces of {n}");
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
