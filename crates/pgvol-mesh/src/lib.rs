//! Triangle meshes for pgvol: the [`Mesh`] type, readers and writers for OBJ, glTF/GLB, STL and
//! PLY, cleaning (welding, degenerate removal) and topology statistics.

use glam::Vec3;

mod atomic;
mod base64;
mod clean;
mod error;
mod format;
mod gltf_io;
mod io;
mod normals;
mod obj;
mod ply;
pub mod shapes;
mod stats;
mod stl;
mod validate;

pub use atomic::write_atomic;
pub use clean::{read_clean, CleanReport};
pub use error::MeshError;
pub use format::MeshFormat;
pub use io::{read, read_bytes, write};
pub use normals::{face_normal, vertex_normals};
pub use stats::MeshStats;
pub use validate::{coordinate_out_of_range, too_small, MAX_COORDINATE, MIN_EXTENT};

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
