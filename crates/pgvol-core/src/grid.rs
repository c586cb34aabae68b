//! The sampling grid shared by every stage: a cube around the mesh with nodes at
//! `origin + spacing * (i, j, k)`, x varying fastest in flat arrays.

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

/// The side of the grid cube relative to the longest extent of the mesh's bounding box.
pub const GRID_MARGIN: f32 = 1.1;

/// A regular grid of nodes. Index `(i, j, k)` lives at `origin + spacing * (i, j, k)` and at flat
/// position `i + nx * (j + ny * k)`, in the local frame; its world position adds `offset`
/// (in f64; zero unless the grid was made for a mesh far from the origin, see
/// [`crate::frame`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    pub origin: Vec3,
    pub spacing: f32,
    pub dims: [usize; 3],
    /// World translation of the local frame. Absent from serialised grids when zero, so grids
    /// near the origin serialise as before it existed.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub offset: DVec3,
}

fn is_zero(v: &DVec3) -> bool {
    *v == DVec3::ZERO
}

/// Why a grid could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error("grid resolution must be at least 2 nodes per axis, got {0}")]
    ResolutionTooSmall(usize),
    #[error("grid would have {0} nodes, more than the limit of {1}")]
    TooManyNodes(u128, u128),
    #[error("voxel size must be a positive finite number, got {0}")]
    BadVoxel(f32),
    #[error("the bounding box is empty or not finite")]
    BadBounds,
}

/// Upper bound on nodes in one grid, 8192³: sparse volumes hold only the band near the surface,
/// so grids this large fit in memory; every dense path checks its own memory estimate first.
pub const MAX_GRID_NODES: u128 = 1 << 39;

impl Grid {
    /// The project convention: a cube of side 1.1 × the longest extent of `[lo, hi]`, centred on the
    /// box, `n` nodes per axis, spacing `side / (n - 1)`.
    pub fn cube_res(lo: Vec3, hi: Vec3, n: usize) -> Result<Grid, GridError> {
        if n < 2 {
            return Err(GridError::ResolutionTooSmall(n));
        }
        let side = cube_side(lo, hi)?;
        Grid::centred((lo + hi) * 0.5, side / (n - 1) as f32, n)
    }

    /// Like [`Grid::cube_res`] but with the spacing given; the node count per axis is the smallest
    /// that covers the cube, and the grid stays centred on the box.
    pub fn cube_voxel(lo: Vec3, hi: Vec3, h: f32) -> Result<Grid, GridError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(GridError::BadVoxel(h));
        }
        let side = cube_side(lo, hi)?;
        let cells = (side / h).ceil().max(1.0) as f64;
        if cells + 1.0 > 1e7 {
            return Err(GridError::TooManyNodes(
                (cells as u128 + 1).pow(3),
                MAX_GRID_NODES,
            ));
        }
        Grid::centred((lo + hi) * 0.5, h, cells as usize + 1)
    }

    fn centred(centre: Vec3, h: f32, n: usize) -> Result<Grid, GridError> {
        let total = (n as u128).pow(3);
        if total > MAX_GRID_NODES {
            return Err(GridError::TooManyNodes(total, MAX_GRID_NODES));
        }
        let half = h * (n - 1) as f32 * 0.5;
        Ok(Grid {
            origin: centre - Vec3::splat(half),
            spacing: h,
            dims: [n, n, n],
            offset: DVec3::ZERO,
        })
    }

    /// Number of nodes.
    #[inline]
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Flat index of node `(i, j, k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Position of node `(i, j, k)`.
    #[inline]
    pub fn point(&self, i: usize, j: usize, k: usize) -> Vec3 {
        self.origin + self.spacing * Vec3::new(i as f32, j as f32, k as f32)
    }

    /// Continuous grid coordinates of a point (node `(i, j, k)` maps to `(i, j, k)`).
    #[inline]
    pub fn to_grid(&self, p: Vec3) -> Vec3 {
        (p - self.origin) / self.spacing
    }

    /// The same grid in the frame translated by `offset` (the local coordinates unchanged).
    pub fn with_offset(self, offset: DVec3) -> Grid {
        Grid { offset, ..self }
    }

    /// The far corner of the grid.
    pub fn max_corner(&self) -> Vec3 {
        self.point(self.dims[0] - 1, self.dims[1] - 1, self.dims[2] - 1)
    }
}

fn cube_side(lo: Vec3, hi: Vec3) -> Result<f32, GridError> {
    let ext = hi - lo;
    if !(lo.is_finite() && hi.is_finite()) || ext.min_element() < 0.0 {
        return Err(GridError::BadBounds);
    }
    let longest = ext.max_element();
    if longest <= 0.0 {
        return Err(GridError::BadBounds);
    }
    Ok(GRID_MARGIN * longest)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cube_res_is_centred_and_spans_the_margin() {
        let g = Grid::cube_res(Vec3::new(0.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 1.0), 12).unwrap();
        assert_eq!(g.dims, [12, 12, 12]);
        assert!((g.spacing - 2.2 / 11.0).abs() < 1e-6);
        let centre = (g.origin + g.max_corner()) * 0.5;
        assert!((centre - Vec3::new(1.0, 0.5, 0.5)).length() < 1e-5);
        assert!((g.max_corner().x - g.origin.x - 2.2).abs() < 1e-5);
    }

    #[test]
    fn cube_voxel_covers_the_cube() {
        let g = Grid::cube_voxel(Vec3::ZERO, Vec3::ONE, 0.3).unwrap();
        assert_eq!(g.dims[0], 5); // ceil(1.1 / 0.3) = 4 cells
        assert!(g.max_corner().x - g.origin.x >= 1.1);
    }

    #[test]
    fn bad_inputs_are_refused() {
        assert!(Grid::cube_res(Vec3::ZERO, Vec3::ONE, 1).is_err());
        assert!(Grid::cube_res(Vec3::ZERO, Vec3::ZERO, 10).is_err());
        assert!(Grid::cube_res(Vec3::ZERO, Vec3::splat(f32::NAN), 10).is_err());
        assert!(Grid::cube_res(Vec3::ZERO, Vec3::ONE, 100_000).is_err());
        assert!(Grid::cube_voxel(Vec3::ZERO, Vec3::ONE, 0.0).is_err());
        assert!(Grid::cube_voxel(Vec3::ZERO, Vec3::ONE, 1e-9).is_err());
    }
}
