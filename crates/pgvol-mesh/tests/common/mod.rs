//! Shared fixtures for the integration tests.
#![allow(dead_code)]

use glam::Vec3;
use pgvol_mesh::Mesh;

/// Unit cube [0,1]^3, vertex i at (i&1, i>>1&1, i>>2&1), outward CCW triangles.
pub fn unit_cube() -> Mesh {
    let positions = (0..8)
        .map(|i| Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32))
        .collect();
    let triangles = vec![
        [0, 2, 3],
        [0, 3, 1], // z = 0
        [4, 5, 7],
        [4, 7, 6], // z = 1
        [0, 1, 5],
        [0, 5, 4], // y = 0
        [2, 6, 7],
        [2, 7, 3], // y = 1
        [0, 4, 6],
        [0, 6, 2], // x = 0
        [1, 3, 7],
        [1, 7, 5], // x = 1
    ];
    Mesh::new(positions, triangles)
}

/// The cube moved and scaled to awkward, non-representable-in-decimal coordinates.
pub fn odd_cube() -> Mesh {
    let mut m = unit_cube();
    for p in &mut m.positions {
        *p = *p * Vec3::new(1.37, 0.1, 2.9e-3) + Vec3::new(0.1, -2.5, 330.0);
    }
    m
}
