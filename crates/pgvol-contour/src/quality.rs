//! Triangle shape statistics.

use pgvol_core::Mesh;

/// Counts of triangles by their smallest angle, in 10° bins: `[0°, 10°)`, `[10°, 20°)`, …,
/// `[50°, 60°]` (no triangle's smallest angle exceeds 60°). Degenerate triangles, whose angles
/// are undefined, count in the first bin.
pub fn min_angle_histogram(mesh: &Mesh) -> [usize; 6] {
    let mut bins = [0usize; 6];
    for t in 0..mesh.triangles.len() {
        let p = mesh.triangle(t).map(|v| v.as_dvec3());
        let angle = |a: usize| {
            let (u, v) = (p[(a + 1) % 3] - p[a], p[(a + 2) % 3] - p[a]);
            // atan2 of |u x v| and u . v stays accurate for small and near-straight angles.
            u.cross(v).length().atan2(u.dot(v)).to_degrees()
        };
        let min = angle(0).min(angle(1)).min(angle(2));
        let bin = if min.is_finite() && min > 0.0 {
            ((min / 10.0) as usize).min(5)
        } else {
            0
        };
        bins[bin] += 1;
    }
    bins
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn bins_by_the_smallest_angle() {
        let h = 3f32.sqrt() / 2.0;
        let positions = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.5, h, 0.0),
            Vec3::new(0.0, 0.1, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
        ];
        let mesh = Mesh::new(positions, vec![[0, 1, 2], [0, 1, 3], [0, 1, 4]]);
        // Equilateral: 60°. Right triangle with legs 1 and 0.1: about 5.7°. Collinear: degenerate.
        assert_eq!(min_angle_histogram(&mesh), [2, 0, 0, 0, 0, 1]);
    }
}
