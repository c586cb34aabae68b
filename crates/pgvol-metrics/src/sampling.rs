//! Area-uniform random points on a mesh surface, reproducible from a seed.

use glam::Vec3;
use pgvol_mesh::Mesh;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// A point on the surface and the unit normal of the triangle it lies on.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceSample {
    pub point: Vec3,
    pub normal: Vec3,
    pub triangle: u32,
}

/// `n` points distributed uniformly by area, or `None` if the mesh has no area.
pub fn sample_surface(mesh: &Mesh, n: usize, seed: u64) -> Option<Vec<SurfaceSample>> {
    let mut cumulative = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0f64;
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        total += 0.5 * (b - a).as_dvec3().cross((c - a).as_dvec3()).length();
        cumulative.push(total);
    }
    if !total.is_finite() || total <= 0.0 {
        return None;
    }
    let mut rng = Pcg64::seed_from_u64(seed);
    let out = (0..n)
        .map(|_| {
            let target = rng.gen::<f64>() * total;
            let t = cumulative
                .partition_point(|&c| c <= target)
                .min(cumulative.len() - 1);
            let [a, b, c] = mesh.triangle(t);
            // Uniform barycentric coordinates by the square-root fold.
            let (r1, r2): (f32, f32) = (rng.gen(), rng.gen());
            let s = r1.sqrt();
            let point = a * (1.0 - s) + b * (s * (1.0 - r2)) + c * (s * r2);
            SurfaceSample {
                point,
                normal: pgvol_mesh::face_normal([a, b, c]),
                triangle: t as u32,
            }
        })
        .collect();
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_follow_area() {
        // Two triangles, the second with three times the area.
        let m = Mesh::new(
            vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::Y,
                Vec3::Z,
                Vec3::Z + Vec3::X * 3.0,
                Vec3::Z + Vec3::Y,
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        );
        let s = sample_surface(&m, 40_000, 9).unwrap();
        let second = s.iter().filter(|s| s.triangle == 1).count() as f64 / 40_000.0;
        assert!((second - 0.75).abs() < 0.01, "{second}");
        assert!(s.iter().all(|s| (s.normal.length() - 1.0).abs() < 1e-5));
        // Same seed, same points.
        let again = sample_surface(&m, 10, 9).unwrap();
        assert_eq!(
            s[..10].iter().map(|s| s.point).collect::<Vec<_>>(),
            again.iter().map(|s| s.point).collect::<Vec<_>>()
        );
    }
}
