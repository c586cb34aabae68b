//! Repairs that make soup-like input (STL, per-face vertices) usable: welding coincident
//! vertices, dropping zero-area triangles and compacting unreferenced vertices.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

use glam::Vec3;
use rayon::prelude::*;

use super::Mesh;

/// Bit pattern of a coordinate with -0.0 folded onto 0.0, so the two zeros weld.
fn key_bits(p: Vec3) -> [u32; 3] {
    p.to_array().map(|c| if c == 0.0 { 0 } else { c.to_bits() })
}

impl Mesh {
    /// Merges vertices that coincide: bit-exactly (treating -0.0 as 0.0) when `tolerance` is 0,
    /// otherwise within `tolerance` of an earlier kept vertex (first-come representatives in a
    /// hash grid, so the cost is linear). Triangles are remapped and unreferenced vertices
    /// removed; a kept vertex keeps its normal. Returns the number of vertices merged into
    /// another.
    pub fn weld(&mut self, tolerance: f32) -> usize {
        let n = self.positions.len();
        let mut rep: Vec<u32> = Vec::with_capacity(n);
        let mut merged = 0;
        if tolerance > 0.0 && tolerance.is_finite() {
            // Cells twice the tolerance wide: a ball of radius `tolerance` then touches at most
            // two cells per axis, the point's own and the neighbour on its nearer side.
            let size = 2.0 * f64::from(tolerance);
            let tol2 = f64::from(tolerance).powi(2);
            // Cell -> most recent representative in it; `next` chains earlier ones.
            let mut heads: HashMap<[i64; 3], u32, FastHash> =
                HashMap::with_capacity_and_hasher(n, FastHash::default());
            let mut next: Vec<u32> = vec![u32::MAX; n];
            for (i, &p) in self.positions.iter().enumerate() {
                let q = p.as_dvec3() / size;
                let cell = q.floor();
                let side = (q - cell).to_array().map(|f| if f < 0.5 { -1 } else { 1 });
                let base = cell.to_array().map(|c| c as i64);
                let mut found = None;
                'search: for mask in 0..8 {
                    let mut key = base;
                    for (axis, k) in key.iter_mut().enumerate() {
                        if mask >> axis & 1 == 1 {
                            *k = k.saturating_add(side[axis]);
                        }
                    }
                    let mut j = heads.get(&key).copied().unwrap_or(u32::MAX);
                    while j != u32::MAX {
                        let other = self.positions[j as usize].as_dvec3();
                        if p.as_dvec3().distance_squared(other) <= tol2 {
                            found = Some(j);
                            break 'search;
                        }
                        j = next[j as usize];
                    }
                }
                match found {
                    Some(j) => {
                        rep.push(j);
                        merged += 1;
                    }
                    None => {
                        rep.push(i as u32);
                        if let Some(old) = heads.insert(base, i as u32) {
                            next[i] = old;
                        }
                    }
                }
            }
        } else {
            let mut first: HashMap<[u32; 3], u32, FastHash> =
                HashMap::with_capacity_and_hasher(n, FastHash::default());
            for (i, &p) in self.positions.iter().enumerate() {
                let j = *first.entry(key_bits(p)).or_insert(i as u32);
                merged += usize::from(j as usize != i);
                rep.push(j);
            }
        }
        for t in &mut self.triangles {
            for i in t.iter_mut() {
                if let Some(&r) = rep.get(*i as usize) {
                    *i = r;
                }
            }
        }
        self.drop_unused_vertices();
        merged
    }

    /// Removes triangles that repeat a vertex or whose cross product is exactly zero (computed
    /// in f64, so tiny but real triangles are kept). Flat triangles with distinct corners are
    /// first folded into the triangle across their long edge (`collinear.rs`), so removing them
    /// opens no crack. Returns how many were removed.
    pub fn drop_degenerate(&mut self) -> usize {
        let folded = super::collinear::fold_collinear(self);
        let before = self.triangles.len();
        let positions = &self.positions;
        self.triangles.retain(|&[a, b, c]| {
            if a == b || b == c || a == c {
                return false;
            }
            let get = |i: u32| positions.get(i as usize).map(|p| p.as_dvec3());
            match (get(a), get(b), get(c)) {
                (Some(p), Some(q), Some(r)) => (q - p).cross(r - p) != glam::DVec3::ZERO,
                // Dangling indices are a validation matter, not degeneracy; keep them visible.
                _ => true,
            }
        });
        folded + before - self.triangles.len()
    }

    /// Removes triangles repeating an earlier one: the same three vertices in the same cyclic
    /// order (repeated faces only multiply the work of every distance query). A pair wound in
    /// opposite directions is a two-sided fin, not a repeat, and stays. Returns how many were
    /// removed.
    pub fn drop_duplicate_triangles(&mut self) -> usize {
        let before = self.triangles.len();
        let mut seen: HashMap<[u32; 3], (), BuildHasherDefault<KeyHasher>> =
            HashMap::with_capacity_and_hasher(before, Default::default());
        self.triangles.retain(|&[a, b, c]| {
            // The rotation starting at the smallest index names the face and its winding.
            let key = if a <= b && a <= c {
                [a, b, c]
            } else if b <= c {
                [b, c, a]
            } else {
                [c, a, b]
            };
            seen.insert(key, ()).is_none()
        });
        before - self.triangles.len()
    }

    /// Removes vertices no triangle refers to, keeping the order of the rest and their normals.
    /// Returns how many were removed.
    pub fn drop_unused_vertices(&mut self) -> usize {
        let n = self.positions.len();
        // Marked and renumbered on every thread; only the compaction, a sequential pass, is
        // serial.
        let used: Vec<AtomicBool> = (0..n).map(|_| AtomicBool::new(false)).collect();
        self.triangles.par_iter().for_each(|t| {
            for &i in t {
                if let Some(u) = used.get(i as usize) {
                    u.store(true, Relaxed);
                }
            }
        });
        let mut new_index = vec![u32::MAX; n];
        let mut kept = 0u32;
        let with_normals = self.normals.len() == n;
        for i in 0..n {
            if used[i].load(Relaxed) {
                new_index[i] = kept;
                self.positions[kept as usize] = self.positions[i];
                if with_normals {
                    self.normals[kept as usize] = self.normals[i];
                }
                kept += 1;
            }
        }
        self.positions.truncate(kept as usize);
        if with_normals {
            self.normals.truncate(kept as usize);
        } else {
            self.normals.clear();
        }
        self.triangles.par_iter_mut().for_each(|t| {
            for i in t {
                // Out-of-range indices stay out of range rather than aliasing a real vertex.
                *i = new_index.get(*i as usize).copied().unwrap_or(u32::MAX);
            }
        });
        n - kept as usize
    }
}

/// Multiply-rotate hashing for integer keys: much faster than SipHash, and weld keys come from
/// geometry, not from an adversary who could exploit collisions to any useful end.
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        // Fold the well-mixed high half into the low bits, which pick the hash bucket.
        self.0 ^ (self.0 >> 32)
    }

    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.write_u64(u64::from_le_bytes(c.try_into().unwrap_or_default()));
        }
        for &b in chunks.remainder() {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u32(&mut self, v: u32) {
        self.write_u64(u64::from(v));
    }

    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(26) ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

type FastHash = BuildHasherDefault<KeyHasher>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn removing_and_welding_vertices_carries_their_normals() {
        // Vertex 1 is unused and vertex 4 repeats vertex 0.
        let positions = vec![Vec3::ZERO, Vec3::ONE, Vec3::X, Vec3::Y, Vec3::ZERO];
        let mut mesh = Mesh::new(positions, vec![[0, 2, 3], [4, 3, 2]]);
        mesh.normals = (0..5).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        assert_eq!(mesh.weld(0.0), 1);
        assert_eq!(mesh.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(
            mesh.normals,
            [0.0, 2.0, 3.0].map(|x| Vec3::new(x, 0.0, 0.0))
        );
        // Normals that do not cover the positions are dropped, not misaligned.
        mesh.normals.pop();
        mesh.triangles.truncate(0);
        mesh.drop_unused_vertices();
        assert!(mesh.normals.is_empty() && mesh.positions.is_empty());
    }

    #[test]
    fn repeated_faces_are_dropped_in_any_rotation_but_opposite_ones_stay() {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let mut mesh = Mesh::new(
            positions,
            vec![
                [0, 1, 2],
                [1, 2, 0],
                [0, 2, 1],
                [0, 1, 3],
                [2, 0, 1],
                [0, 1, 2],
            ],
        );
        assert_eq!(mesh.drop_duplicate_triangles(), 3);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 1], [0, 1, 3]]);
    }
}
