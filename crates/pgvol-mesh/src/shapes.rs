//! Simple closed meshes with known geometry, for tests, examples and fixtures.

use glam::Vec3;
use std::collections::HashMap;

use crate::Mesh;

/// The axis-aligned box `[lo, hi]`: 8 vertices (vertex `i` at the corner picked by the bits of
/// `i`: x, y, z), 12 outward, counter-clockwise triangles.
pub fn cuboid(lo: Vec3, hi: Vec3) -> Mesh {
    let positions = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let triangles = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    Mesh::new(positions, triangles)
}

/// A unit sphere approximated by an octahedron whose triangles are split in four `levels` times,
/// new vertices projected onto the sphere: `8 · 4^levels` outward triangles.
pub fn octasphere(levels: u32) -> Mesh {
    let mut positions = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..levels {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push(((positions[a as usize] + positions[b as usize]) * 0.5).normalize());
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let ab = mid(a, b, &mut positions);
            let bc = mid(b, c, &mut positions);
            let ca = mid(c, a, &mut positions);
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        triangles = next;
    }
    Mesh::new(positions, triangles)
}

/// A prism over the regular `sides`-gon of radius 1 between z = −1 and z = 1, its caps fanned
/// from their centres: `4 · sides` outward triangles. With many sides its walls are needles
/// 2 long, the triangles on which distance and winding-number queries are hardest.
pub fn prism(sides: u32) -> Mesh {
    let n = sides.max(3);
    let mut positions = Vec::with_capacity(2 * n as usize + 2);
    for z in [-1.0, 1.0] {
        positions.extend((0..n).map(|i| {
            let a = std::f32::consts::TAU * i as f32 / n as f32;
            Vec3::new(a.cos(), a.sin(), z)
        }));
    }
    positions.extend([Vec3::NEG_Z, Vec3::Z]);
    let (bottom, top) = (2 * n, 2 * n + 1);
    let triangles = (0..n)
        .flat_map(|i| {
            let j = (i + 1) % n;
            [
                [i, j, n + j],
                [i, n + j, n + i],
                [bottom, j, i],
                [top, n + i, n + j],
            ]
        })
        .collect();
    Mesh::new(positions, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_closed_and_outward() {
        let c = cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)).stats();
        assert!(c.watertight && c.winding_consistent && c.euler_characteristic == 2);
        assert!((c.volume - 6.0).abs() < 1e-9 && (c.area - 22.0).abs() < 1e-9);
        let s = octasphere(3);
        assert_eq!(s.triangles.len(), 8 * 64);
        let st = s.stats();
        assert!(st.watertight && st.winding_consistent && st.euler_characteristic == 2);
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        assert!(st.volume > 0.9 * ball && st.volume < ball);
        assert!(s.positions.iter().all(|p| (p.length() - 1.0).abs() < 1e-6));
    }

    #[test]
    fn prism_is_closed_and_outward_with_the_polygons_volume() {
        let p = prism(1000);
        let st = p.stats();
        assert!(st.watertight && st.winding_consistent && st.non_manifold_edges == 0);
        assert_eq!(p.triangles.len(), 4000);
        // Area of the regular 1000-gon times the height 2.
        let n = 1000.0f64;
        let polygon = n / 2.0 * (std::f64::consts::TAU / n).sin();
        assert!((st.volume - 2.0 * polygon).abs() < 1e-4, "{}", st.volume);
    }
}
