//! Which cells get a stored vertex: those near a crease or corner of the exact contour where the
//! smooth fit's vertex is off the exact one.

use glam::Vec3;
use pgvol_contour::DualMesh;
use pgvol_core::{Grid, Mesh};
use rayon::prelude::*;

use super::cells::{cell_at, cell_keys, key_of, single_vertices, CellVertex};

/// The edges of `mesh` where the normals of its two triangles differ by more than `angle`
/// (radians), as `(a, b, s, t)`: the vertices of the edge and its two triangles. The sign of a
/// normal is ignored, so inconsistent winding makes no feature; only edges sharper than 180°
/// less `angle` would be missed. This needs no distance query: a shape without any is smooth
/// and costs nothing more.
pub(crate) fn sharp_edges(mesh: &Mesh, angle: f32) -> SharpEdges {
    let normals: Vec<Vec3> = mesh
        .triangles
        .par_iter()
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
    // Equal entries are identical, so the parallel sort's order is the sequential one.
    edges.par_sort_unstable();
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
    flat: &FlatSides,
    closest: &ClosestTriangle,
) -> Vec<u64> {
    let normals = &sharp.normals;
    let sharp: Vec<(u32, u32)> = sharp
        .edges
        .par_iter()
        .filter(|&&(a, b, s, t)| {
            let test = CreaseTest {
                mesh,
                normals,
                h: grid.spacing,
                cos: sharp.cos,
                flat,
                closest,
            };
            test.holds((a, b), (s, t))
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

/// What tells a crease that turns by less than `below` from the facets of a coarse curved
/// surface: the surface on either side stays flat, within `turn`, from one cell to `reach`
/// cells away from it. A curved surface's facets are flat too, but their neighbours a few
/// cells on turn again; the faces beside a part's creases do not.
pub(crate) struct FlatSides {
    /// Cosine of the crease angle below which the sides must be flat.
    pub cos_below: f32,
    /// Cells away from the edge where the surface is compared with its value one cell away.
    pub reach: f32,
    /// Cosine of the largest turn allowed between the two.
    pub cos_turn: f32,
}

impl FlatSides {
    /// From angles in degrees.
    pub(crate) fn new(below: f32, reach: f32, turn: f32) -> Self {
        FlatSides {
            cos_below: below.to_radians().cos(),
            reach,
            cos_turn: turn.to_radians().cos(),
        }
    }
}

/// What deciding whether one sharp edge is a crease at the grid's scale needs.
struct CreaseTest<'a> {
    mesh: &'a Mesh,
    normals: &'a [Vec3],
    /// The grid spacing.
    h: f32,
    /// Cosine of the crease angle.
    cos: f32,
    flat: &'a FlatSides,
    closest: &'a ClosestTriangle<'a>,
}

impl CreaseTest<'_> {
    /// Whether the surface one cell away on either side of the sharp edge `(a, b)` between
    /// triangles `(s, t)` still turns by more than the crease angle (`|cos| < cos`), a scan's
    /// noise making sharp edges between tiny triangles whose neighbourhoods, a cell away, are
    /// parallel; and, for an edge turning by less than [`FlatSides`]' angle, whether both sides
    /// are flat.
    fn holds(&self, (a, b): (u32, u32), (s, t): (u32, u32)) -> bool {
        let mesh = self.mesh;
        let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        let middle = 0.5 * (p + q);
        let along = (q - p).normalize_or_zero();
        // The normals of the surface one cell and `reach` cells away on triangle `tri`'s side.
        let away = |tri: u32| -> Option<[Vec3; 2]> {
            let n = self.normals[tri as usize];
            let third = mesh.triangles[tri as usize]
                .iter()
                .map(|&v| mesh.positions[v as usize])
                .find(|&x| x != p && x != q)?;
            let mut d = n.cross(along);
            if d.dot(third - middle) < 0.0 {
                d = -d;
            }
            let near = (self.closest)(middle + d * self.h)?;
            let far = (self.closest)(middle + d * (self.flat.reach * self.h))?;
            Some([near, far].map(|f| self.normals[f as usize]))
        };
        let (Some([m, m_far]), Some([n, n_far])) = (away(s), away(t)) else {
            return true;
        };
        let turn = m.dot(n).abs();
        if turn >= self.cos {
            return false;
        }
        let own = self.normals[s as usize].dot(self.normals[t as usize]).abs();
        let steep = turn < self.flat.cos_below && own < self.flat.cos_below;
        // Signed: a side whose far normal faces the other way (another sheet, or inconsistent
        // winding) is not flat.
        steep || (m.dot(m_far) > self.flat.cos_turn && n.dot(n_far) > self.flat.cos_turn)
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
    exact: &DualMesh,
    smooth: &Mesh,
    grid: &Grid,
    tolerance: f32,
    closest: &(dyn Fn(Vec3) -> Option<Vec3> + Sync),
) -> Vec<(u64, Vec3)> {
    let exact_cells = single_vertices(&exact.mesh, &exact.homes, grid);
    let smooth_cells = single_vertices(smooth, &[], grid);
    let exact_keys = cell_keys(&exact.mesh, &exact.homes, grid);
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

    /// 17³ nodes a quarter apart about the origin.
    fn test_grid() -> Grid {
        Grid {
            origin: Vec3::splat(-2.0),
            spacing: 0.25,
            dims: [17, 17, 17],
            offset: Default::default(),
        }
    }

    #[test]
    fn a_cube_edge_is_a_feature_and_a_flat_square_is_not() {
        let grid = test_grid();
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
        let rule = FlatSides::new(50.0, 8.0, 3.0);
        let cells = feature_cells(&edge, &sharp_edges(&edge, angle), &grid, 2.0, &rule, &none);
        assert_eq!(cells.len(), 5, "{cells:?}");
        assert!(cells.contains(&key_of(&grid, [8, 8, 8])));
        let flat = Mesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        assert!(sharp_edges(&flat, angle).edges.is_empty());
        let short = feature_cells(&edge, &sharp_edges(&edge, angle), &grid, 5.0, &rule, &none);
        assert!(short.is_empty());
    }

    /// A 40° crease between two wide flat faces is one; the 40° edges of a nine-sided prism,
    /// whose facets are narrower than the reach, are not.
    #[test]
    fn a_shallow_crease_needs_flat_sides() {
        let grid = test_grid();
        let angle = 30f32.to_radians();
        let flat = FlatSides::new(50.0, 8.0, 3.0);
        let features = |mesh: &Mesh| {
            let bvh = pgvol_sdf::Bvh::build(mesh);
            let closest = |p| bvh.closest(p, f32::INFINITY).map(|c| c.triangle);
            feature_cells(mesh, &sharp_edges(mesh, angle), &grid, 2.0, &flat, &closest)
        };
        let up = 3.0 * Vec3::new(0.0, 40f32.to_radians().cos(), 40f32.to_radians().sin());
        let roof = Mesh::new(
            vec![
                Vec3::new(-1.5, 0.0, 0.0),
                Vec3::new(1.5, 0.0, 0.0),
                Vec3::new(1.5, -3.0, 0.0),
                Vec3::new(-1.5, -3.0, 0.0),
                Vec3::new(1.5, 0.0, 0.0) + up,
                Vec3::new(-1.5, 0.0, 0.0) + up,
            ],
            vec![[0, 2, 1], [0, 3, 2], [0, 1, 4], [0, 4, 5]],
        );
        assert_eq!(sharp_edges(&roof, angle).edges.len(), 1);
        assert!(features(&roof).len() >= 12, "{:?}", features(&roof));

        let sides = 9;
        let ring = |z: f32| {
            (0..sides).map(move |k| {
                let a = std::f32::consts::TAU * k as f32 / sides as f32;
                Vec3::new(a.cos(), a.sin(), z)
            })
        };
        let positions: Vec<Vec3> = ring(-1.5).chain(ring(1.5)).collect();
        let triangles = (0..sides as u32)
            .flat_map(|k| {
                let next = (k + 1) % sides as u32;
                let s = sides as u32;
                [[k, next, next + s], [k, next + s, k + s]]
            })
            .collect();
        let prism = Mesh::new(positions, triangles);
        assert_eq!(sharp_edges(&prism, angle).edges.len(), sides);
        assert!(features(&prism).is_empty(), "{:?}", features(&prism));
    }
}
