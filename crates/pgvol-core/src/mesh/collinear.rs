//! Flat triangles whose corners are distinct but collinear (a sliver of a large polygon's
//! triangulation once its corners are rounded to f32) are folded into their neighbour before
//! they are dropped, so that dropping them leaves no crack.
//!
//! A flat triangle (a, b, c) with b between a and c covers no area, but its edges a→b and b→c
//! are the only partners of the neighbours' b→a and c→b. Dropping it alone leaves those edges
//! open, and the open edges make the sign follow winding numbers evaluated node by node near
//! them (slow on a mesh of thousands of such edges). Splitting the triangle across its long
//! edge, (a, c, x), at b into (a, b, x) and (b, c, x) keeps the surface and closes the mesh.

use std::collections::HashMap;

use glam::DVec3;

use super::Mesh;

/// Folds every flat triangle with distinct corners into the triangle across its long edge
/// (see the module doc) and removes it. A flat triangle whose long edge has no single partner
/// (a rim, or a non-manifold edge) is left for [`Mesh::drop_degenerate`]. Returns how many
/// were folded.
pub(super) fn fold_collinear(mesh: &mut Mesh) -> usize {
    let positions = &mesh.positions;
    let corner = |i: u32| positions.get(i as usize).map(|p| p.as_dvec3());
    let flat = |t: [u32; 3]| match (corner(t[0]), corner(t[1]), corner(t[2])) {
        (Some(p), Some(q), Some(r)) => {
            p != q && q != r && p != r && (q - p).cross(r - p) == DVec3::ZERO
        }
        _ => false,
    };
    let mut queue: Vec<u32> = (0..mesh.triangles.len() as u32)
        .filter(|&t| flat(mesh.triangles[t as usize]))
        .collect();
    if queue.is_empty() {
        return 0;
    }
    // Directed edge → its triangle; `None` once a second triangle claims the same edge.
    let mut edges: HashMap<(u32, u32), Option<u32>> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for e in directed(*tri) {
            edges
                .entry(e)
                .and_modify(|v| *v = None)
                .or_insert(Some(t as u32));
        }
    }
    let mut alive = vec![true; mesh.triangles.len()];
    let mut folded = 0;
    // Each fold removes one flat triangle and may create two; a cascade along a run of
    // collinear corners ends at a triangle with a corner off the line. The cap is a guard.
    let mut budget = 4 * mesh.triangles.len() + 16;
    while let Some(t) = queue.pop() {
        if budget == 0 {
            break;
        }
        budget -= 1;
        if !alive[t as usize] {
            continue;
        }
        let tri = mesh.triangles[t as usize];
        let [a, b, c] = middle_second(tri, &corner);
        let Some(Some(n)) = edges.get(&(a, c)).copied() else {
            continue;
        };
        if n == t || !alive[n as usize] {
            continue;
        }
        let x = opposite(mesh.triangles[n as usize], a, c);
        if x == b {
            continue;
        }
        for e in directed(tri)
            .into_iter()
            .chain(directed(mesh.triangles[n as usize]))
        {
            edges.remove(&e);
        }
        alive[t as usize] = false;
        let first = [a, b, x];
        let second = [b, c, x];
        mesh.triangles[n as usize] = first;
        let s = mesh.triangles.len() as u32;
        mesh.triangles.push(second);
        alive.push(true);
        for (id, tri) in [(n, first), (s, second)] {
            for e in directed(tri) {
                edges.entry(e).and_modify(|v| *v = None).or_insert(Some(id));
            }
            if flat(tri) {
                queue.push(id);
            }
        }
        folded += 1;
    }
    let mut keep = alive.into_iter();
    mesh.triangles.retain(|_| keep.next().unwrap_or(true));
    folded
}

fn directed([a, b, c]: [u32; 3]) -> [(u32, u32); 3] {
    [(a, b), (b, c), (c, a)]
}

/// The triangle rotated so that its middle corner (the one between the other two on their
/// line) comes second: the long edge is then the third, c → a.
fn middle_second(tri: [u32; 3], corner: &impl Fn(u32) -> Option<DVec3>) -> [u32; 3] {
    let p = tri.map(|i| corner(i).unwrap_or(DVec3::ZERO));
    let length = |i: usize| p[i].distance_squared(p[(i + 1) % 3]);
    let long = (0..3).fold(0, |best, i| if length(i) > length(best) { i } else { best });
    // Edge `long` runs from corner `long` to `long + 1`; the middle corner is `long + 2`.
    [tri[(long + 1) % 3], tri[(long + 2) % 3], tri[long]]
}

/// The corner of `tri` that is neither `a` nor `c` (`tri` holds the edge a → c).
fn opposite(tri: [u32; 3], a: u32, c: u32) -> u32 {
    tri.into_iter().find(|&v| v != a && v != c).unwrap_or(a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn volume(mesh: &Mesh) -> f64 {
        mesh.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// A square pyramid whose front base edge carries an extra vertex 5 at its middle, used by
    /// the split front side and by a flat triangle (0, 1, 5) under a base triangle spanning
    /// the edge: closed only with the flat triangle.
    fn pyramid_with_a_flat_base_sliver() -> Mesh {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 2.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(1.0, 1.0, 1.5),
            Vec3::new(1.0, 0.0, 0.0),
        ];
        let triangles = vec![
            [0, 5, 4],
            [5, 1, 4],
            [1, 2, 4],
            [2, 3, 4],
            [3, 0, 4],
            [0, 2, 1],
            [0, 3, 2],
            [0, 1, 5],
        ];
        Mesh::new(positions, triangles)
    }

    #[test]
    fn a_flat_sliver_is_folded_into_its_neighbour_and_the_mesh_stays_closed() {
        let mut mesh = pyramid_with_a_flat_base_sliver();
        assert!(mesh.stats().watertight);
        let before = volume(&mesh);
        assert_eq!(fold_collinear(&mut mesh), 1);
        assert_eq!(mesh.triangles.len(), 8);
        let stats = mesh.stats();
        assert!(stats.watertight && stats.winding_consistent, "{stats:?}");
        assert!((volume(&mesh) - before).abs() < 1e-9);
        assert_eq!(mesh.drop_degenerate(), 0);
    }

    #[test]
    fn a_run_of_collinear_corners_cascades_to_a_fan() {
        // A flat polygon's rim along y = 0 with seven collinear corners, triangulated by
        // halving so that slivers nest, closed by a roof to the apex 8.
        let mut positions: Vec<Vec3> = (0..7).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        positions.push(Vec3::new(3.0, 4.0, 0.0));
        positions.push(Vec3::new(3.0, 1.0, 2.0));
        let mut triangles = vec![
            [0, 1, 2],
            [2, 3, 4],
            [4, 5, 6],
            [0, 2, 4],
            [0, 4, 6],
            [0, 6, 7],
        ];
        let rim: Vec<u32> = (0..7).chain([7]).collect();
        for w in 0..rim.len() {
            let (u, v) = (rim[w], rim[(w + 1) % rim.len()]);
            triangles.push([v, u, 8]);
        }
        let mut mesh = Mesh::new(positions, triangles);
        assert!(mesh.stats().watertight);
        let before = volume(&mesh);
        assert_eq!(fold_collinear(&mut mesh), 5);
        assert_eq!(mesh.drop_degenerate(), 0);
        let stats = mesh.stats();
        assert!(stats.watertight && stats.winding_consistent, "{stats:?}");
        assert!((volume(&mesh) - before).abs() < 1e-6);
    }

    /// Random soups on a small lattice, where collinear corners abound: folding never opens an
    /// edge and keeps the signed volume.
    #[test]
    fn folding_random_soups_keeps_their_edges_and_volume() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |m: u64| {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 33) % m
        };
        let positions: Vec<Vec3> = (0..18)
            .map(|i| Vec3::new((i % 3) as f32, (i / 3 % 3) as f32, (i / 9) as f32))
            .collect();
        for _ in 0..2000 {
            let count = 2 + next(12) as usize;
            let triangles = (0..count)
                .map(|_| [next(18) as u32, next(18) as u32, next(18) as u32])
                .collect();
            let mut mesh = Mesh::new(positions.clone(), triangles);
            let (edges, before) = (mesh.stats().boundary_edges, volume(&mesh));
            fold_collinear(&mut mesh);
            assert!(mesh.stats().boundary_edges <= edges);
            assert!((volume(&mesh) - before).abs() < 1e-9);
        }
    }
}
