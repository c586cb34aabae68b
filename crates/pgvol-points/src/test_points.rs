//! Points the tests share.

use glam::Vec3;

/// `n` points spread evenly (Fibonacci lattice) on a sphere of radius `r` at the origin.
pub fn sphere_points(n: usize, r: f32) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let rho = (1.0 - y * y).sqrt();
            let phi = golden * i as f32;
            Vec3::new(rho * phi.cos(), y, rho * phi.sin()) * r
        })
        .collect()
}
