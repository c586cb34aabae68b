//! The exact signed distance of a mesh as a field for contouring, so `remesh` places vertices
//! on the input surface itself rather than on a smoothed fit of it.

use glam::Vec3;
use pgvol_contour::Field;
use pgvol_core::Mesh;
use pgvol_sdf::MeshSdf;

/// Exact node distances within this many grid spacings of the surface when remeshing; farther
/// nodes need only their sign, since contouring reads values only at crossed edges.
pub const NODE_BAND: f32 = 2.5;

/// Below this fraction of a grid spacing from the surface, `p − closest` is mostly rounding,
/// so the closest triangle's own normal is the gradient.
const ON_SURFACE: f32 = 1e-3;

/// Signed distance to a mesh with its gradient: `(p − closest) / distance` times the sign away
/// from the surface, the unit normal of the closest triangle on it.
pub struct MeshField<'a> {
    mesh: &'a Mesh,
    sdf: &'a MeshSdf,
    on_surface: f32,
}

impl<'a> MeshField<'a> {
    /// `sdf` must have been built from `mesh`; `spacing` is the contouring grid's.
    pub fn new(mesh: &'a Mesh, sdf: &'a MeshSdf, spacing: f32) -> Self {
        Self {
            mesh,
            sdf,
            on_surface: ON_SURFACE * spacing,
        }
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

impl Field for MeshField<'_> {
    fn value(&self, p: Vec3) -> f32 {
        self.sdf.signed_distance(p)
    }

    fn value_gradient(&self, p: Vec3) -> (f32, Vec3) {
        let Some(c) = self.sdf.bvh().closest(p, f32::INFINITY) else {
            return (f32::INFINITY, Vec3::ZERO);
        };
        let d = c.distance_squared.sqrt();
        let sign = if self.sdf.is_inside_near(p, &c) {
            -1.0
        } else {
            1.0
        };
        let gradient = if d > self.on_surface {
            (p - c.point) * (sign / d)
        } else {
            self.face_normal(c.triangle)
        };
        (sign * d, gradient)
    }
}
