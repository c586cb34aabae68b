//! Normals for clouds that have none (Hoppe et al. 1992): the direction of least spread of each
//! point's k nearest neighbours (PCA), then one orientation for all, propagated from the
//! topmost point (whose normal must point up) along a minimum spanning tree of the
//! neighbour graph weighted by 1 − |nᵢ·nⱼ|, so orientation crosses smooth regions first.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;

use crate::index::PointIndex;

/// Neighbours per point for the plane fit and the orientation graph.
pub const NORMAL_NEIGHBOURS: usize = 12;

/// The [`NORMAL_NEIGHBOURS`] nearest points of each of `points` (mean spacing `spacing`), the
/// point itself included.
pub(crate) fn nearest_neighbours(points: &[Vec3], spacing: f32) -> Vec<Vec<u32>> {
    let index = PointIndex::new(points, spacing.max(f32::MIN_POSITIVE) * 2.0);
    let reach = far_reach(points);
    points
        .par_iter()
        .map_init(Vec::new, |near, &p| {
            index.nearest(p, NORMAL_NEIGHBOURS + 1, reach, near);
            near.iter().map(|&(_, j)| j).collect()
        })
        .collect()
}

/// Unit normals of `points`, estimated and consistently oriented (outward for a closed cloud
/// sampled densely enough that the neighbour graph does not jump between sheets).
pub fn estimate_normals(points: &[Vec3], spacing: f32) -> Vec<Vec3> {
    let neighbours = nearest_neighbours(points, spacing);
    let mut normals: Vec<Vec3> = neighbours
        .par_iter()
        .map(|near| plane_normal(points, near))
        .collect();
    orient(points, &neighbours, &mut normals);
    normals
}

pub(crate) fn far_reach(points: &[Vec3]) -> f32 {
    let (lo, hi) = crate::index::bounds(points);
    (hi - lo).length() * 2.0 + 1.0
}

/// The eigenvector of the smallest eigenvalue of the neighbours' covariance.
fn plane_normal(points: &[Vec3], near: &[u32]) -> Vec3 {
    if near.len() < 3 {
        return Vec3::Z;
    }
    let mean = near
        .iter()
        .map(|&j| points[j as usize].as_dvec3())
        .sum::<DVec3>()
        / near.len() as f64;
    let mut cov = DMat3::ZERO;
    for &j in near {
        let d = points[j as usize].as_dvec3() - mean;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    smallest_eigenvector(cov).as_vec3()
}

/// Smallest eigenvector of a symmetric 3×3 matrix by cyclic Jacobi rotations.
pub fn smallest_eigenvector(m: DMat3) -> DVec3 {
    let mut a = m.to_cols_array_2d();
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-300 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * rp[k] - s * rq[k];
                a[q][k] = s * rp[k] + c * rq[k];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let i = (0..3)
        .min_by(|&x, &y| a[x][x].total_cmp(&a[y][y]))
        .unwrap_or(2);
    let n = DVec3::new(v[0][i], v[1][i], v[2][i]);
    n.try_normalize().unwrap_or(DVec3::Z)
}

/// Flips normals so neighbours agree: Prim's tree from the topmost unvisited point of each
/// connected part, its normal turned to +z (the topmost point of a closed surface faces up).
pub(crate) fn orient(points: &[Vec3], neighbours: &[Vec<u32>], normals: &mut [Vec3]) {
    let n = points.len();
    let mut done = vec![false; n];
    let mut by_height: Vec<u32> = (0..n as u32).collect();
    by_height.sort_unstable_by(|&a, &b| points[b as usize].z.total_cmp(&points[a as usize].z));
    let mut heap = BinaryHeap::new();
    for &seed in &by_height {
        let seed = seed as usize;
        if done[seed] {
            continue;
        }
        if normals[seed].z < 0.0 {
            normals[seed] = -normals[seed];
        }
        heap.push((Reverse(0u32), seed as u32, seed as u32));
        while let Some((_, i, from)) = heap.pop() {
            let i = i as usize;
            if done[i] {
                continue;
            }
            done[i] = true;
            if normals[i].dot(normals[from as usize]) < 0.0 {
                normals[i] = -normals[i];
            }
            for &j in &neighbours[i] {
                if !done[j as usize] {
                    let cost = 1.0 - normals[i].dot(normals[j as usize]).abs();
                    // Costs in [0, 1] as ordered integers for the heap.
                    let key = (cost.clamp(0.0, 1.0) * 1e9) as u32;
                    heap.push((Reverse(key), j, i as u32));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigenvector_of_a_flat_spread_is_its_normal() {
        let m = DMat3::from_diagonal(DVec3::new(3.0, 0.01, 2.0));
        let n = smallest_eigenvector(m);
        assert!((n.y.abs() - 1.0).abs() < 1e-9, "{n}");
        let r = DMat3::from_rotation_x(0.7);
        let n = smallest_eigenvector(r * m * r.transpose());
        assert!((n.dot(r * DVec3::Y).abs() - 1.0).abs() < 1e-9, "{n}");
    }

    #[test]
    fn sphere_normals_come_out_outward() {
        let points = crate::test_points::sphere_points(2000, 1.0);
        let normals = estimate_normals(&points, crate::index::mean_spacing(&points));
        let outward = points
            .iter()
            .zip(&normals)
            .filter(|(p, n)| p.normalize().dot(**n) > 0.95)
            .count();
        assert_eq!(outward, points.len());
    }
}
