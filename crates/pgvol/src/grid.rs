//! The grid convention: a cube of side 1.1 × the mesh's longest extent, centred on it.

use pgvol_core::{Grid, Mesh};

use crate::error::{Error, ErrorKind, Result};

/// Nodes per axis when neither a resolution nor a spacing is given.
pub const DEFAULT_RES: usize = 128;

/// The fewest nodes per axis accepted: fewer cannot hold a cubic B-spline's support inside.
pub const MIN_RES: u32 = 4;

/// The most nodes per axis accepted: a 400 mm part at 50 µm. The sparse encode, decode and slice
/// hold the band near the surface; each job estimates its memory first and refuses with the
/// figure when it would not fit (at 8192³ on 24 GB, parts with little surface fit).
pub const MAX_RES: u32 = 8192;

/// How the grid around a mesh is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridSpec {
    /// This many nodes per axis.
    Res(usize),
    /// This spacing, in mesh units; the node count covers the cube.
    Voxel(f32),
}

impl Default for GridSpec {
    fn default() -> Self {
        GridSpec::Res(DEFAULT_RES)
    }
}

impl GridSpec {
    /// The grid around `mesh`, in the mesh's frame (its local coordinates, its offset).
    pub fn grid_for(self, mesh: &Mesh) -> Result<Grid> {
        let (lo, hi) = mesh
            .bounds()
            .ok_or_else(|| Error::new(ErrorKind::InputFile, "the mesh has no triangles"))?;
        Ok(self.grid_for_box(lo, hi)?.with_offset(mesh.offset))
    }

    /// The grid around the box `[lo, hi]` (of a point cloud, say).
    pub fn grid_for_box(self, lo: glam::Vec3, hi: glam::Vec3) -> Result<Grid> {
        let grid = match self {
            GridSpec::Res(n) => Grid::cube_res(lo, hi, n),
            GridSpec::Voxel(h) => Grid::cube_voxel(lo, hi, h),
        };
        Ok(grid?)
    }
}
