//! The signed distance sampled at the nodes, and points moved along its gradient onto a level.

use glam::Vec3;
use pgvol_core::Grid;
use rayon::prelude::*;

use crate::distance::SignedDistance;

/// The SDF and its gradient at every node (x fastest).
pub(crate) struct NodeSdf {
    pub distance: Vec<f32>,
    pub gradient: Vec<Vec3>,
}

impl NodeSdf {
    pub(crate) fn sample(grid: &Grid, sdf: &dyn SignedDistance) -> NodeSdf {
        let [nx, ny, _] = grid.dims;
        let pairs: Vec<(f32, Vec3)> = (0..grid.len())
            .into_par_iter()
            .map(|idx| {
                let (i, j, k) = (idx % nx, (idx / nx) % ny, idx / (nx * ny));
                sdf.distance_gradient(grid.point(i, j, k))
            })
            .collect();
        let (distance, gradient) = pairs.into_iter().unzip();
        NodeSdf { distance, gradient }
    }
}

/// Moves `p` along the SDF gradient until the SDF equals `target` (exact for a true distance
/// function away from its medial axis; two steps absorb curvature of an approximate one).
pub(crate) fn project(sdf: &dyn SignedDistance, p: Vec3, d: f32, n: Vec3, target: f32) -> Vec3 {
    let mut q = p - (d - target) * n;
    for _ in 0..2 {
        let (dq, nq) = sdf.distance_gradient(q);
        if (dq - target).abs() < 1e-7 || !nq.is_finite() {
            break;
        }
        q -= (dq - target) * nq;
    }
    q
}
