//! The indexed triangle mesh every stage passes around; reading and writing files is
//! `pgvol-mesh`'s job.

mod clean;
mod components;
mod orient;
mod stats;

use glam::Vec3;

pub use stats::MeshStats;

/// An indexed triangle mesh in the units of its source file.
///
/// Triangles are counter-clockwise seen from outside (right-hand rule gives the outward normal).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Self {
        Self {
            positions,
            triangles,
        }
    }

    /// The three corners of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Axis-aligned bounds of the vertices referenced by triangles, `None` when there are none.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.triangles.iter().flatten();
        let first = self.positions[*it.next()? as usize];
        let (mut lo, mut hi) = (first, first);
        for &i in it {
            let p = self.positions[i as usize];
            lo = lo.min(p);
            hi = hi.max(p);
        }
        Some((lo, hi))
    }
}
