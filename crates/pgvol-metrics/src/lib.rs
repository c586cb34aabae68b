//! Surface distance metrics between two meshes, the measuring stick of every stage: symmetric
//! Hausdorff, Chamfer-L1 and normal deviation from area-uniform samples and exact
//! point-to-triangle distances, plus the topology statistics of both meshes.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]
#![forbid(unsafe_code)]

pub mod depth_buffer;
pub mod sampling;
pub mod vertex_deviation;

use glam::{Vec3, Vec3A};
use pgvol_mesh::{Mesh, MeshStats};
use pgvol_sdf::Bvh;
use rayon::prelude::*;
use serde::Serialize;

pub use depth_buffer::{depth_difference, DepthDifference, ViewDifference, DEPTH_RESOLUTION};
pub use sampling::{sample_surface, SurfaceSample};
pub use vertex_deviation::{vertex_deviation, VertexDeviation};

/// The result of comparing mesh A against reference mesh B.
#[derive(Clone, Debug, Serialize)]
pub struct Comparison {
    pub a: MeshStats,
    pub b: MeshStats,
    /// Samples drawn on each mesh.
    pub samples: usize,
    /// Bounding-box diagonal of B, the unit of the `_pct` figures.
    pub diagonal: f64,
    pub hausdorff: f64,
    pub hausdorff_pct: f64,
    pub chamfer_l1: f64,
    pub chamfer_l1_pct: f64,
    pub mean_a_to_b: f64,
    pub mean_b_to_a: f64,
    /// Angle between the normals at each sample and at its closest point on the other mesh,
    /// pooled over both directions, in degrees.
    pub normal_deviation_mean_deg: f64,
    pub normal_deviation_p95_deg: f64,
    /// Distance from each vertex of A to B and the angle between A's vertex normal and B's
    /// normal there (the perturbation paper's first two measures).
    pub vertex_deviation: VertexDeviation,
    pub vertex_deviation_mean_pct: f64,
    pub vertex_deviation_max_pct: f64,
    /// Mean absolute difference of depth buffers rendered from the 14 views of
    /// [`depth_buffer`] (the paper's third measure), and as % of the diagonal.
    pub depth_buffer: DepthDifference,
    pub depth_buffer_pct: f64,
}

/// Distances and normal angles from samples on one mesh to the closest points of another.
struct OneWay {
    distances: Vec<f64>,
    angles: Vec<f64>,
}

fn one_way(samples: &[SurfaceSample], target: &Mesh, bvh: &Bvh) -> OneWay {
    let pairs: Vec<(f64, f64)> = samples
        .par_iter()
        .map(|s| {
            let c = bvh
                .closest(s.point, f32::INFINITY)
                .expect("target mesh has triangles");
            let n = pgvol_mesh::face_normal(target.triangle(c.triangle as usize));
            let cos = s.normal.dot(n).clamp(-1.0, 1.0) as f64;
            ((c.distance_squared as f64).sqrt(), cos.acos().to_degrees())
        })
        .collect();
    let (distances, angles) = pairs.into_iter().unzip();
    OneWay { distances, angles }
}

/// Why two meshes could not be compared.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CompareError {
    /// The named mesh ("A" or "B") has no triangle of positive area.
    NoArea(&'static str),
}

impl std::fmt::Display for CompareError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CompareError::NoArea(which) => write!(f, "mesh {which} has no surface area to sample"),
        }
    }
}

impl std::error::Error for CompareError {}

/// Compares A against B with `samples` area-uniform samples on each, drawn from `seed`.
pub fn compare(a: &Mesh, b: &Mesh, samples: usize, seed: u64) -> Result<Comparison, CompareError> {
    let sa = sample_surface(a, samples, seed).ok_or(CompareError::NoArea("A"))?;
    let sb = sample_surface(b, samples, seed.wrapping_add(1)).ok_or(CompareError::NoArea("B"))?;
    let (bvh_a, bvh_b) = rayon::join(|| Bvh::build(a), || Bvh::build(b));
    let ab = one_way(&sa, b, &bvh_b);
    let ba = one_way(&sb, a, &bvh_a);
    let vertices = vertex_deviation(a, b, &bvh_b);
    let depth = depth_difference(a, b, DEPTH_RESOLUTION).ok_or(CompareError::NoArea("B"))?;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let max = |v: &[f64]| v.iter().cloned().fold(0.0, f64::max);
    let (lo, hi) = b.bounds().ok_or(CompareError::NoArea("B"))?;
    let diagonal = (hi - lo).as_dvec3().length();
    let pct = |x: f64| {
        if diagonal > 0.0 {
            100.0 * x / diagonal
        } else {
            0.0
        }
    };
    let hausdorff = max(&ab.distances).max(max(&ba.distances));
    let (mean_a_to_b, mean_b_to_a) = (mean(&ab.distances), mean(&ba.distances));
    let chamfer = 0.5 * (mean_a_to_b + mean_b_to_a);
    let mut angles: Vec<f64> = ab.angles.iter().chain(&ba.angles).cloned().collect();
    angles.sort_by(f64::total_cmp);
    let p95 = angles
        .get(((angles.len() as f64 * 0.95) as usize).min(angles.len().saturating_sub(1)))
        .cloned()
        .unwrap_or(0.0);
    Ok(Comparison {
        a: a.stats(),
        b: b.stats(),
        samples,
        diagonal,
        hausdorff,
        hausdorff_pct: pct(hausdorff),
        chamfer_l1: chamfer,
        chamfer_l1_pct: pct(chamfer),
        mean_a_to_b,
        mean_b_to_a,
        normal_deviation_mean_deg: mean(&angles),
        normal_deviation_p95_deg: p95,
        vertex_deviation_mean_pct: pct(vertices.mean),
        vertex_deviation_max_pct: pct(vertices.max),
        vertex_deviation: vertices,
        depth_buffer_pct: pct(depth.mean_abs),
        depth_buffer: depth,
    })
}

/// Exact distance from `p` to the mesh by checking every triangle (for tests and small meshes).
pub fn brute_force_distance(mesh: &Mesh, p: Vec3) -> f32 {
    (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            let corners = [a, b, c].map(Vec3A::from);
            pgvol_sdf::triangle::closest_point_and_distance(
                p.into(),
                corners[0],
                corners[1],
                corners[2],
            )
            .2
        })
        .fold(f32::INFINITY, f32::min)
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    use pgvol_mesh::shapes::cuboid as box_mesh;

    #[test]
    fn identical_meshes_are_at_distance_zero() {
        let m = box_mesh(Vec3::ZERO, Vec3::ONE);
        let c = compare(&m, &m, 5000, 1).unwrap();
        assert!(c.hausdorff < 1e-6 && c.chamfer_l1 < 1e-7);
        assert!(c.normal_deviation_p95_deg < 1e-2);
        assert!((c.diagonal - 3f64.sqrt()).abs() < 1e-6);
        assert!(c.vertex_deviation.max < 1e-6 && c.vertex_deviation.normal_max_deg < 1e-2);
        assert_eq!(c.depth_buffer_pct, 0.0);
    }

    #[test]
    fn nested_boxes_match_brute_force_and_geometry() {
        let a = box_mesh(Vec3::splat(0.1), Vec3::splat(0.9));
        let b = box_mesh(Vec3::ZERO, Vec3::ONE);
        let c = compare(&a, &b, 4000, 7).unwrap();
        // Every face of A is 0.1 inside B: A-to-B distances are exactly 0.1.
        assert!((c.mean_a_to_b - 0.1).abs() < 1e-5);
        // A's corners are 0.1 from B's nearest faces too.
        assert!((c.vertex_deviation.mean - 0.1).abs() < 1e-5);
        assert!((c.vertex_deviation.max - 0.1).abs() < 1e-5);
        // From B's corners the farthest point of A is at distance 0.1·√3.
        assert!(c.hausdorff <= 0.1 * 3f64.sqrt() + 1e-5 && c.hausdorff > 0.1);
        // Compare the B-to-A mean with a brute-force evaluation on the same samples.
        let samples = sample_surface(&b, 4000, 8).unwrap();
        let brute: f64 = samples
            .iter()
            .map(|s| brute_force_distance(&a, s.point) as f64)
            .sum::<f64>()
            / 4000.0;
        assert!(
            (brute - c.mean_b_to_a).abs() < 1e-6,
            "{brute} vs {}",
            c.mean_b_to_a
        );
    }

    #[test]
    fn flipped_normals_show_as_180_degrees() {
        let a = box_mesh(Vec3::ZERO, Vec3::ONE);
        let mut b = a.clone();
        for t in &mut b.triangles {
            t.swap(1, 2);
        }
        let c = compare(&a, &b, 1000, 3).unwrap();
        assert!(c.normal_deviation_mean_deg > 179.0);
    }

    #[test]
    fn meshes_without_area_are_refused() {
        let flat = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], vec![[0, 1, 2]]);
        let b = box_mesh(Vec3::ZERO, Vec3::ONE);
        assert_eq!(
            compare(&flat, &b, 100, 1).err(),
            Some(CompareError::NoArea("A"))
        );
    }
}
