//! Which cells get a stored vertex: those near a crease or corner of the exact contour where the
//! smooth fit's vertex is off the exact one.

use glam::Vec3;
use pgvol_core::{Grid, Mesh};

use super::cells::{cell_at, cell_keys, key_of, single_vertices, CellVertex};

/// The edges of `mesh` where the normals of its two triangles differ by more than `angle`
/// (radians), as `(a, b, s, t)`: the vertices of the edge and its two triangles. The sign of a
/// normal is ignored, so inconsistent winding makes no feature; only edges sharper than 180°
/// less `angle` would be missed. This needs no distance query: a shape without any is smooth
/// and costs nothing more.
pub(crate) fn sharp_edges(mesh: &Mesh, angle: f32) -> SharpEdges {
    let normals: Vec<Vec3> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            (b - a).cross(c - a).normalize_or_zero()
        })
        .collect();
    let mut edges: Vec<(u32, u32, u32)> = mesh
        .triangles
        .iter()
        .enumerate()
        .flat_map(|(t, tri)| {
            (0..3).map(move |e| {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                (a.min(b), a.max(b), t as u32)
            })
        })
        .collect();
    edges.sort_unstable();
    let cos = angle.cos();
    let edges = edges
        .windows(2)
        .filter(|pair| {
            let ((a, b, s), (c, d, t)) = (pair[0], pair[1]);
            (a, b) == (c, d) && normals[s as usize].dot(normals[t as usize]).abs() < cos
        })
        .map(|pair| (pair[0].0, pair[0].1, pair[0].2, pair[1].2))
        .collect();
    SharpEdges {
        normals,
        edges,
        cos,
    }
}

/// What [`sharp_edges`] found.
pub(crate) struct SharpEdges {
    /// Unit normal of each triangle.
    normals: Vec<Vec3>,
    /// `(a, b, s, t)`: the edge's vertices and its two triangles.
    pub edges: Vec<(u32, u32, u32, u32)>,
    /// Cosine of the crease angle.
    cos: f32,
}

/// The cells of `grid` that a crease of `mesh` passes through: an edge of `sharp` whose
/// surface still turns by more than the angle a cell away on either side (`closest` gives the
/// triangle of the mesh closest to a point), on a chain of such edges at least `min_length`
/// cells long. A scan's noise and the facets of a coarse smooth mesh make short, isolated sharp
/// edges that the grid does not resolve as creases.
pub(crate) fn feature_cells(
    mesh: &Mesh,
    sharp: &SharpEdges,
    grid: &Grid,
    min_length: f32,
    closest: &ClosestTriangle,
) -> Vec<u64> {
    let (normals, cos) = (&sharp.normals, sharp.cos);
    let sharp: Vec<(u32, u32)> = sharp
        .edges
        .iter()
        .filter(|&&(a, b, s, t)| {
            crease_at_grid_scale(mesh, normals, (a, b), (s, t), grid.spacing, cos, closest)
        })
        .map(|&(a, b, _, _)| (a, b))
        .collect();
    let sharp = long_creases(mesh, &sharp, min_length * grid.spacing);
    // Points along a sharp edge at most half a cell apart reach every cell it passes through.
    let step = 0.5 * grid.spacing;
    let mut keys = Vec::new();
    for (a, b) in sharp {
        let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        let n = ((p.distance(q) / step).ceil() as usize).max(1);
        for k in 0..=n {
            let x = p.lerp(q, k as f32 / n as f32);
            if let Some(key) = cell_containing(grid, x) {
                keys.push(key);
            }
        }
    }
    keys.sort_unstable();
    keys.dedup();
    keys
}

/// The triangle of the mesh closest to a point.
pub(crate) type ClosestTriangle<'a> = dyn Fn(Vec3) -> Option<u32> + Sync + 'a;

/// Whether the surface one cell away on either side of the sharp edge `(a, b)` between
/// triangles `(s, t)` still turns by more than the crease angle (`|cos| < cos`): a scan's noise
/// makes sharp edges between tiny triangles whose neighbourhoods, a cell away, are parallel.
fn crease_at_grid_scale(
    mesh: &Mesh,
    normals: &[Vec3],
    (a, b): (u32, u32),
    (s, t): (u32, u32),
    h: f32,
    cos: f32,
    closest: &ClosestTriangle,
) -> bool {
    let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
    let middle = 0.5 * (p + q);
    let along = (q - p).normalize_or_zero();
    let away = |tri: u32| -> Option<Vec3> {
        let n = normals[tri as usize];
        let third = mesh.triangles[tri as usize]
            .iter()
            .map(|&v| mesh.positions[v as usize])
            .find(|&x| x != p && x != q)?;
        let mut d = n.cross(along);
        if d.dot(third - middle) < 0.0 {
            d = -d;
        }
        let far = closest(middle + d * h)?;
        Some(normals[far as usize])
    };
    match (away(s), away(t)) {
        (Some(m), Some(n)) => m.dot(n).abs() < cos,
        _ => true,
    }
}

/// The edges of `sharp` on chains (edges joined at their ends) of total length `min_length` or
/// more.
fn long_creases(mesh: &Mesh, sharp: &[(u32, u32)], min_length: f32) -> Vec<(u32, u32)> {
    let mut parent: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    for &(a, b) in sharp {
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut length = vec![0f32; mesh.positions.len()];
    let length_of =
        |(a, b): (u32, u32)| mesh.positions[a as usize].distance(mesh.positions[b as usize]);
    for &e in sharp {
        length[root(&mut parent, e.0) as usize] += length_of(e);
    }
    sharp
        .iter()
        .copied()
        .filter(|&(a, _)| length[root(&mut parent, a) as usize] >= min_length)
        .collect()
}

/// The key of the cell of `grid` holding `p`, faces included; `None` outside the grid.
fn cell_containing(grid: &Grid, p: Vec3) -> Option<u64> {
    let u = ((p - grid.origin) / grid.spacing).floor();
    let cells = grid.dims.map(|n| n as f32 - 1.0);
    let inside = (0..3).all(|a| u[a] >= 0.0 && u[a] < cells[a]);
    inside.then(|| key_of(grid, u.to_array().map(|x| x as u64)))
}

/// The stored cells among `owned` (ascending keys of `grid`), with the vertex of each in cell
/// units: the cells whose single vertex in `smooth` lies farther than `tolerance` from the one
/// it should have: the single vertex of that cell in `exact`, or, in a cell the exact contour
/// does not cross (the rounded surface left it), the point of the surface `closest` to the
/// smooth vertex, kept in the cell. `exact` and `smooth` are contours on any grid sharing
/// `grid`'s nodes whose interior holds the owned cells.
pub(crate) fn stored_cells(
    owned: &[u64],
    exact: &Mesh,
    smooth: &Mesh,
    grid: &Grid,
    tolerance: f32,
    closest: &(dyn Fn(Vec3) -> Option<Vec3> + Sync),
) -> Vec<(u64, Vec3)> {
    let exact_cells = single_vertices(exact, grid);
    let smooth_cells = single_vertices(smooth, grid);
    let exact_keys = cell_keys(exact, grid);
    let h = grid.spacing;
    smooth_cells
        .iter()
        .filter(|s| owned.binary_search(&s.key).is_ok())
        .filter_map(|s| {
            let target = match find(&exact_cells, s.key) {
                Some(e) => e.local,
                None if exact_keys.binary_search(&s.key).is_ok() => return None,
                None => {
                    let p = smooth.positions[s.vertex as usize];
                    let corner = p - s.local * h;
                    ((closest(p)? - corner) / h).clamp(Vec3::ZERO, Vec3::ONE)
                }
            };
            (s.local.distance(target) > tolerance).then_some((s.key, target))
        })
        .collect()
}

fn find(cells: &[CellVertex], key: u64) -> Option<&CellVertex> {
    cells
        .binary_search_by_key(&key, |c| c.key)
        .ok()
        .map(|i| &cells[i])
}

/// The keys of the cells within `ring` cells per axis of one of `keys`, ascending.
pub(crate) fn within_ring(keys: &[u64], grid: &Grid, ring: u64) -> Vec<u64> {
    let cells = grid.dims.map(|n| n as u64 - 1);
    let mut out = Vec::with_capacity(keys.len() * (2 * ring as usize + 1).pow(2));
    for &key in keys {
        let c = cell_at(grid, key);
        let lo = c.map(|x| x.saturating_sub(ring));
        let hi = [0, 1, 2].map(|a| (c[a] + ring).min(cells[a] - 1));
        for k in lo[2]..=hi[2] {
            for j in lo[1]..=hi[1] {
                for i in lo[0]..=hi[0] {
                    out.push(key_of(grid, [i, j, k]));
                }
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cube_edge_is_a_feature_and_a_flat_square_is_not() {
        let grid = Grid {
            origin: Vec3::splat(-2.0),
            spacing: 0.25,
            dims: [17, 17, 17],
            offset: Default::default(),
        };
        let angle = 30f32.to_radians();
        // Two faces of a cube meeting along the x axis from 0 to 1, and a flat square.
        let edge = Mesh::new(
            vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 0.0, 1.0),
            ],
            vec![[0, 1, 2], [1, 0, 3]],
        );
        let none = |_| None;
        let cells = feature_cells(&edge, &sharp_edges(&edge, angle), &grid, 2.0, &none);
        assert_eq!(cells.len(), 5, "{cells:?}");
        assert!(cells.contains(&key_of(&grid, [8, 8, 8])));
        let flat = Mesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        assert!(sharp_edges(&flat, angle).edges.is_empty());
        assert!(feature_cells(&edge, &sharp_edges(&edge, angle), &grid, 5.0, &none).is_empty());
    }
}
