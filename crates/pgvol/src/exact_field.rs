//! The exact signed distance of a mesh as a field for contouring, so `remesh` places vertices
//! on the input surface itself rather than on a smoothed fit of it.

use glam::Vec3;
use pgvol_contour::Field as ContourField;
use pgvol_core::{Grid, Mesh};
use pgvol_sdf::{Closest, MeshSdf, SegmentHit, SignMode};

/// Exact node distances within this many grid spacings of the surface when remeshing; farther
/// nodes need only their sign, since contouring reads values only at crossed edges.
pub const NODE_BAND: f32 = 2.5;

/// Below this fraction of a grid spacing from the surface, `p − closest` is mostly rounding,
/// so the closest triangle's own normal is the gradient.
const ON_SURFACE: f32 = 1e-3;

/// Within this fraction of a grid spacing, segment crossings are too close to their end to
/// count (on long thin triangles the closest point itself is only this accurate in f32), and
/// a point takes the side of its closest face's plane when no node lends it a sign.
const NEAR_SURFACE: f32 = 1e-2;

/// Signed distance to a mesh with its gradient: `(p − closest) / distance` times the sign away
/// from the surface, the unit normal of the closest triangle on it.
pub struct MeshField<'a> {
    mesh: &'a Mesh,
    sdf: &'a MeshSdf,
    on_surface: f32,
    near_surface: f32,
    nodes: Option<NodeSigns<'a>>,
    /// Signs asked for and signs computed afresh, to check how rarely the latter happens.
    #[cfg(test)]
    signs: [std::sync::atomic::AtomicUsize; 2],
}

/// Signed samples of a grid whose signs the field's points may borrow: off a closed mesh the
/// winding number is the same at both ends of a segment whose signed surface crossings cancel,
/// so a point takes the sign of a cell corner it is joined to that way. That costs one short
/// segment query where a winding number costs a walk over the whole mesh, which on long thin
/// triangles opens nearly every node.
struct NodeSigns<'a> {
    grid: &'a Grid,
    values: &'a [f32],
}

impl<'a> MeshField<'a> {
    /// `sdf` must have been built from `mesh`; `spacing` is the contouring grid's.
    pub fn new(mesh: &'a Mesh, sdf: &'a MeshSdf, spacing: f32) -> Self {
        Self {
            mesh,
            sdf,
            on_surface: ON_SURFACE * spacing,
            near_surface: NEAR_SURFACE * spacing,
            nodes: None,
            #[cfg(test)]
            signs: Default::default(),
        }
    }

    /// [`MeshField::new`] on `grid`'s spacing, whose points take their sign from the nearby
    /// nodes of `grid` when the sign is a whole winding number (a closed mesh, see
    /// [`MeshSdf::winding_is_whole`]); `values` (x fastest) must carry the signs `sdf` gives
    /// the nodes.
    pub fn with_node_signs(
        mesh: &'a Mesh,
        sdf: &'a MeshSdf,
        grid: &'a Grid,
        values: &'a [f32],
    ) -> Self {
        // Off a closed mesh the winding number is constant between crossings; near the rims of
        // an open one it varies, and a node's sign says nothing exact about its neighbourhood.
        let closed = sdf.winding_is_whole();
        let nodes = (closed && values.len() == grid.len()).then_some(NodeSigns { grid, values });
        Self {
            nodes,
            ..Self::new(mesh, sdf, grid.spacing)
        }
    }

    /// Whether `p` is inside, given its closest point on the mesh. The pseudonormal answers
    /// from the closest point alone; the other signs cost a walk over the mesh, which on long
    /// thin triangles opens nearly every node, so they are tried last:
    /// 1. on the surface (where the gradient is the closest face's normal), the side of that
    ///    face's plane;
    /// 2. a node's sign, when one is joined to `p` without a net surface crossing;
    /// 3. within `near_surface`, the side of the closest face's plane again: there crossings
    ///    are too close to `p` to count and a wrong side moves a root by less than that;
    /// 4. the sign computed afresh.
    fn is_inside(&self, p: Vec3, closest: &Closest) -> bool {
        #[cfg(test)]
        self.signs[0].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if self.sdf.sign_mode() != SignMode::Pseudonormal {
            let plane_side = || (p - closest.point).dot(self.face_normal(closest.triangle)) < 0.0;
            let within = |d: f32| closest.distance_squared <= d * d;
            if within(self.on_surface) {
                return plane_side();
            }
            if let Some(inside) = self.nodes.as_ref().and_then(|n| n.inside(self.sdf, p)) {
                return inside;
            }
            if self.nodes.is_some() && within(self.near_surface) {
                return plane_side();
            }
        }
        #[cfg(test)]
        self.signs[1].fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.sdf.is_inside_near(p, closest)
    }

    /// The crossing of the grid edge from `a` to `b` (along `axis`, `a` inside when
    /// `a_inside`) and the normal there, from the mesh itself: where the edge meets its one
    /// crossed triangle, and that triangle's normal, exact on a planar face and on either side
    /// of a crease (a root found on the distance sees the crease's blended closest points
    /// instead). `None` where the edge meets no triangle, several, or one within rounding of
    /// its border, or one facing against the nodes' signs (inconsistent winding): the caller
    /// finds those on the distance.
    pub fn edge_hermite(
        &self,
        a: Vec3,
        b: Vec3,
        axis: usize,
        a_inside: bool,
    ) -> Option<(Vec3, Vec3)> {
        let SegmentHit::One { point, normal, .. } = self.sdf.bvh().segment_hit(a, b) else {
            return None;
        };
        let outwards = if a_inside {
            normal[axis]
        } else {
            -normal[axis]
        };
        (outwards > 0.0).then_some((point, normal))
    }

    /// Outward unit normal of triangle `t` (counter-clockwise seen from outside), zero when it
    /// is degenerate or out of range.
    fn face_normal(&self, t: u32) -> Vec3 {
        let corner = |i: u32| self.mesh.positions.get(i as usize).copied();
        let corners = self
            .mesh
            .triangles
            .get(t as usize)
            .and_then(|&[a, b, c]| Some([corner(a)?, corner(b)?, corner(c)?]));
        match corners {
            Some([a, b, c]) => (b - a).cross(c - a).normalize_or_zero(),
            None => Vec3::ZERO,
        }
    }
}

impl ContourField for MeshField<'_> {
    fn value(&self, p: Vec3) -> f32 {
        self.value_gradient(p).0
    }

    fn value_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let Some(c) = self.sdf.bvh().closest(p, f32::INFINITY) else {
            return (f32::INFINITY, Vec3::ZERO);
        };
        let d = c.distance_squared.sqrt();
        let sign = if self.is_inside(p, &c) { -1.0 } else { 1.0 };
        let gradient = if d > self.on_surface {
            (p - c.point) * (sign / d)
        } else {
            self.face_normal(c.triangle)
        };
        (sign * d, gradient)
    }
}

impl NodeSigns<'_> {
    /// The sign of the first corner of `p`'s cell, nearest first, that `p` is joined to
    /// without a net surface crossing; `None` when every segment is unsure or crosses.
    fn inside(&self, sdf: &MeshSdf, p: Vec3) -> Option<bool> {
        let grid = self.grid;
        let u = grid.to_grid(p);
        if !u.is_finite() || grid.dims.iter().any(|&n| n < 2) {
            return None;
        }
        let last = grid.dims.map(|n| n.saturating_sub(2) as f32);
        let base = u.floor().clamp(Vec3::ZERO, Vec3::from(last));
        let mut corners: [(f32, [usize; 3]); 8] = std::array::from_fn(|c| {
            let corner = base + Vec3::new((c & 1) as f32, (c >> 1 & 1) as f32, (c >> 2) as f32);
            let [i, j, k] = corner.to_array().map(|x| x as usize);
            (corner.distance_squared(u), [i, j, k])
        });
        corners.sort_by(|a, b| a.0.total_cmp(&b.0));
        corners.into_iter().find_map(|(_, [i, j, k])| {
            let value = *self.values.get(grid.index(i, j, k))?;
            // A node on the surface has no sign to lend.
            if value == 0.0 || value.is_nan() {
                return None;
            }
            match sdf.bvh().winding_jump(grid.point(i, j, k), p) {
                Some(0) => Some(value < 0.0),
                _ => None,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pgvol_contour::{contour_field, DualContourOptions, Method};
    use pgvol_mesh::shapes::{octasphere, prism};
    use pgvol_sdf::sampling::Extent;
    use std::sync::atomic::Ordering;

    fn grid_around(mesh: &Mesh, n: usize) -> Grid {
        let (lo, hi) = mesh.bounds().unwrap();
        let margin = (hi - lo).max_element() * 0.05;
        Grid::cube_res(lo - margin, hi + margin, n).unwrap()
    }

    /// Points spread through `grid` (a fixed low-discrepancy sequence).
    fn spread(grid: &Grid, count: usize) -> impl Iterator<Item = Vec3> + '_ {
        let extent = grid.max_corner() - grid.origin;
        (1..=count).map(move |i| {
            let f = |a: f64| ((i as f64 * a).fract()) as f32;
            grid.origin + extent * Vec3::new(f(0.754_877_666), f(0.569_840_291), f(0.430_159_709))
        })
    }

    #[test]
    fn borrowed_signs_agree_with_the_winding_number_away_from_the_surface() {
        // Open (a sphere with its top cut off) and overlapping (two spheres' union as a soup):
        // the meshes whose sign is the winding number.
        let mut open = octasphere(3);
        open.triangles
            .retain(|t| t.iter().all(|&i| open.positions[i as usize].z < 0.7));
        let mut overlapping = octasphere(3);
        let shifted = octasphere(3);
        let base = overlapping.positions.len() as u32;
        overlapping.positions.extend(
            shifted
                .positions
                .iter()
                .map(|p| *p + Vec3::new(0.8, 0.3, 0.1)),
        );
        overlapping
            .triangles
            .extend(shifted.triangles.iter().map(|t| t.map(|i| i + base)));
        for (mesh, closed) in [(open, false), (overlapping, true)] {
            let sdf = MeshSdf::new(&mesh, SignMode::Winding).unwrap();
            let grid = grid_around(&mesh, 24);
            let values = sdf.sample(&grid, Extent::Band(NODE_BAND), &|_| {}).values;
            let field = MeshField::with_node_signs(&mesh, &sdf, &grid, &values);
            let mut compared = 0;
            for p in spread(&grid, 4000) {
                let expected = sdf.signed_distance(p);
                if expected.abs() > field.near_surface {
                    assert_eq!(field.value(p).signum(), expected.signum(), "{p}");
                    compared += 1;
                }
            }
            assert!(compared > 3000);
            // Most signs were borrowed, not computed afresh, where the mesh is closed; an open
            // mesh's winding number varies between crossings, so nothing is borrowed.
            let [asked, fresh] = field.signs.each_ref().map(|s| s.load(Ordering::Relaxed));
            assert!(asked >= compared, "{asked} {compared}");
            assert_eq!(field.nodes.is_some(), closed);
            if closed {
                assert!(
                    fresh * 100 < asked,
                    "{fresh} of {asked} signs computed afresh"
                );
            }
        }
    }

    #[test]
    fn a_many_sided_prism_remeshes_with_borrowed_signs_as_with_pseudonormals() {
        // Its sides are needles, on which a winding number opens nearly every node of the tree.
        let mesh = prism(5000);
        let grid = grid_around(&mesh, 24);
        let options = DualContourOptions {
            feature_offset: 0.0,
            ..DualContourOptions::default()
        };
        let contour = |mode| {
            let sdf = MeshSdf::new(&mesh, mode).unwrap();
            let values = sdf.sample(&grid, Extent::Band(NODE_BAND), &|_| {}).values;
            let field = MeshField::with_node_signs(&mesh, &sdf, &grid, &values);
            let out = contour_field(
                &field,
                &grid,
                &values,
                0.0,
                Method::DualContouring,
                &options,
                pgvol_core::progress::QUIET,
            )
            .unwrap();
            (
                out,
                field.signs.each_ref().map(|s| s.load(Ordering::Relaxed)),
            )
        };
        let (winding, [asked, fresh]) = contour(SignMode::Winding);
        let (pseudonormal, _) = contour(SignMode::Pseudonormal);
        assert!(
            asked > 1000 && fresh * 100 < asked,
            "{fresh} of {asked} signs computed afresh"
        );
        // The same cells hold the same vertices (a quad's diagonal may differ with them).
        assert_eq!(winding.triangles.len(), pseudonormal.triangles.len());
        assert_eq!(winding.positions.len(), pseudonormal.positions.len());
        let moved = winding
            .positions
            .iter()
            .zip(&pseudonormal.positions)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0f32, f32::max);
        assert!(
            moved <= NEAR_SURFACE * grid.spacing,
            "a vertex moved {moved}"
        );
    }
}
