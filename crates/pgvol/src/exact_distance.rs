//! The exact signed distance of a mesh, oriented and with its distance queries built once, for
//! contouring the mesh itself on several grids (remeshing with the exact field, and the
//! sharp-feature cells encoding stores).

use std::time::Instant;

use pgvol_contour::{DualContourOptions, DualMesh, Method};
use pgvol_core::{Grid, Mesh};
use pgvol_sdf::sampling::Extent;
use pgvol_sdf::SignMode;

use crate::distance::{oriented, sample};
use crate::error::{Error, ErrorKind, Result};
use crate::exact_field::{MeshField, NODE_BAND};
use crate::progress::{self, Progress};
use crate::timings::Timings;

/// A mesh oriented for its exact distance, with its distance queries built once for
/// contouring on several grids.
pub(crate) struct ExactDistance<'m> {
    // The exact field's gradients on the surface come from the faces: oriented first.
    mesh: std::borrow::Cow<'m, Mesh>,
    sdf: pgvol_sdf::MeshSdf,
}

impl<'m> ExactDistance<'m> {
    pub(crate) fn new(mesh: &'m Mesh, sign: SignMode) -> Result<Self> {
        let mesh = oriented(mesh, sign);
        let sdf = pgvol_sdf::MeshSdf::new(&mesh, sign)?;
        Ok(Self { mesh, sdf })
    }

    /// The mesh's distance queries.
    pub(crate) fn sdf(&self) -> &pgvol_sdf::MeshSdf {
        &self.sdf
    }

    /// The distance queries alone, the oriented mesh dropped.
    pub(crate) fn into_sdf(self) -> pgvol_sdf::MeshSdf {
        self.sdf
    }

    /// The closest-point hierarchy of the oriented mesh (the same triangles, in the same
    /// order, as the mesh given).
    pub(crate) fn bvh(&self) -> &pgvol_sdf::Bvh {
        self.sdf.bvh()
    }

    /// The surface contoured on `grid` (see [`contour_exact`]); the distance stage's time,
    /// counted from `start`, and the contour's go to `timings`.
    pub(crate) fn contour(
        &self,
        grid: &Grid,
        method: Method,
        timings: &mut Timings,
        start: Instant,
        progress: &dyn Progress,
    ) -> Result<Mesh> {
        let sampled = sample(&self.sdf, grid, Extent::Band(NODE_BAND), progress)?;
        timings.sdf = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let field = MeshField::with_node_signs(&self.mesh, &self.sdf, grid, &sampled.values);
        let options = DualContourOptions {
            feature_offset: 0.0,
            ..DualContourOptions::default()
        };
        let out = progress::stage(progress, "contour", |update| {
            let values = &sampled.values;
            pgvol_contour::contour_field(&field, grid, values, 0.0, method, &options, update)
        })?
        .map_err(|e| Error::new(ErrorKind::Internal, e.to_string()).caused_by(e))?;
        timings.contour = start.elapsed().as_secs_f64();
        Ok(out)
    }

    /// The surface dual-contoured on `grid` with the Hermite data of the mesh's own faces
    /// (`MeshField::edge_hermite`): one segment query per crossed edge instead of a root
    /// search on the distance, and exact normals on both sides of a crease. Edges the faces do
    /// not answer are found as [`Self::contour`] finds them, and smooth cells' vertices are
    /// projected onto the distance's zero set as there. A vertex may leave its cell by up to
    /// `reach` cells (`DualContourOptions::reach`); the mesh comes with each vertex's cell.
    /// With `only`, just those cells' vertices and no triangles.
    pub(crate) fn contour_from_faces(
        &self,
        grid: &Grid,
        reach: f32,
        only: Option<&pgvol_contour::CellSet>,
        progress: &dyn Progress,
    ) -> Result<DualMesh> {
        let sampled = sample(&self.sdf, grid, Extent::Band(NODE_BAND), progress)?;
        let field = MeshField::with_node_signs(&self.mesh, &self.sdf, grid, &sampled.values);
        // The projection of smooth cells' vertices onto the distance's zero set costs a
        // closest-point query per cell (8 % of `--sharp auto`'s time on fandisk at 256³); it
        // keeps the vertices of curved faces on them (without it, bench_sharp's rocker arm at a
        // 30° crease angle: 4.52° against 4.48°, and 2 % more cells stored on fandisk).
        let options = DualContourOptions {
            feature_offset: 0.0,
            reach,
            ..DualContourOptions::default()
        };
        let hermite = |a, b, axis, a_inside| field.edge_hermite(a, b, axis, a_inside);
        progress::stage(progress, "contour", |update| {
            let values = &sampled.values;
            pgvol_contour::contour_field_hermite(
                &field, grid, values, 0.0, &options, &hermite, only, update,
            )
        })?
        .map_err(|e| Error::new(ErrorKind::Internal, e.to_string()).caused_by(e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;
    use glam::{Mat3, Vec3};

    /// A cube turned off the axes, contoured with its faces' Hermite data: the vertices lie on
    /// its surface but in the cells along its edges whose planes meet outside the cell (there
    /// the vertex is kept in the cell), and its corners are vertices but where a corner's cell
    /// is one of those.
    #[test]
    fn face_hermite_data_put_vertices_on_the_faces_and_corners() {
        let turn = Mat3::from_rotation_y(0.4) * Mat3::from_rotation_x(0.7);
        let mut cube = pgvol_mesh::shapes::cuboid(Vec3::splat(-0.5), Vec3::splat(0.5));
        for p in &mut cube.positions {
            *p = turn * *p;
        }
        let grid = Grid::cube_res(Vec3::splat(-1.0), Vec3::splat(1.0), 24).unwrap();
        let exact = ExactDistance::new(&cube, SignMode::Auto).unwrap();
        let out = exact
            .contour_from_faces(&grid, 0.0, None, &Silent)
            .unwrap()
            .mesh;
        let h = grid.spacing;
        // Signed distance from the cube, in its own frame.
        let from_cube = |p: Vec3| {
            let q = (turn.transpose() * p).abs() - Vec3::splat(0.5);
            q.max(Vec3::ZERO).length() + q.max_element().min(0.0)
        };
        let off = out
            .positions
            .iter()
            .filter(|&&p| from_cube(p).abs() > 1e-3 * h)
            .count();
        // 48 of 958 measured.
        assert!(
            off * 100 <= 6 * out.positions.len(),
            "{off} of {} vertices off the cube",
            out.positions.len()
        );
        let corners: Vec<f32> = cube
            .positions
            .iter()
            .map(|c| {
                let nearest = out.positions.iter().map(|p| p.distance(*c));
                nearest.fold(f32::INFINITY, f32::min) / h
            })
            .collect();
        let exact_corners = corners.iter().filter(|&&d| d < 1e-3).count();
        assert!(
            exact_corners >= 6 && corners.iter().all(|&d| d < 0.1),
            "corners off by {corners:?} spacings"
        );
    }
}
