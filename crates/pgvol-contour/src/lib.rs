//! Contouring of sampled scalar fields into closed, consistently oriented triangle meshes.
//!
//! Three methods share the conventions below: [`marching_cubes`] (vertices on grid edges),
//! [`dual_contour`] (one vertex per surface component of a cell, placed by the tangent planes
//! of a continuous [`Field`], so sharp features survive; same topology guarantees as marching
//! cubes) and [`surface_nets`] (the same topology, each vertex at the mean of its crossings
//! moved onto the field).
//! [`min_angle_histogram`] reports triangle quality.
//!
//! [`marching_cubes`] extracts the iso-surface of values sampled on a regular grid. Unlike the
//! classic 256-entry table, the cell triangulations here are derived by tracing the contour
//! around each cube face, with ambiguous faces resolved by the asymptotic decider on that face's
//! four values alone, so neighbouring cells always agree and the output has these guarantees:
//!
//! * **Welded**: one vertex per grid edge crossed by the surface, shared by the cells around it.
//! * **Watertight and manifold**: wherever the inside region stays away from the grid border,
//!   every edge has exactly two triangles and the triangles around every vertex form one disk.
//! * **Oriented**: triangles are counter-clockwise seen from outside, i.e. normals point towards
//!   increasing values, so a closed surface around a negative region has positive signed volume.
//! * **No degenerate triangles**: vertices keep a small margin from the grid nodes, and no three
//!   crossings of one cell are collinear.
//! * **Deterministic**: the work runs in parallel over blocks of 8³ cells, but vertex and
//!   triangle order do not depend on the number of threads.
//! * **Sparse**: one read of the samples finds the blocks whose nodes straddle iso; only those
//!   are visited again, so the cost beyond that read grows with the surface, not the volume.
//!
//! Conventions: a node is inside when its value is `< iso` and outside otherwise (`>= iso`), so a
//! signed distance field (negative inside) gives outward-facing triangles. NaN counts as outside.
//! Where inside nodes lie on the grid border the surface is left open there; callers wanting a
//! closed mesh pad the grid with outside values.

mod blocks;
mod cells;
mod components;
mod crossings;
mod cube;
mod cubic_eval;
mod decider;
mod dual;
mod edge_cubic;
mod extract;
mod field;
mod place;
mod project;
mod qef;
mod quads;
mod quality;
mod root;
mod samples;
mod sparse_sample;
mod table;
mod triangulate;
mod volume;

pub use field::Field;
pub use quality::min_angle_histogram;
pub use volume::{contour_field, contour_sampled, contour_volume, resampled_grid, Method};

use glam::Vec3;
use pgvol_core::Mesh;
use rayon::prelude::*;

use crate::crossings::{all_crossings, with_normal, Place, PlaceWithNormal};
use crate::dual::Placement;
use crate::extract::{block_triangles, Part, EXTRA_FLAG};
use crate::root::cubic_edge_root;
use crate::samples::Samples;

/// Extracts the surface `value == iso` of a grid of samples, placing each vertex on its grid edge
/// by linear interpolation of the two node values.
///
/// `values` is indexed x fastest, `values[i + dims[0] * (j + dims[1] * k)]` being the sample at
/// `origin + spacing * (i, j, k)`. See the crate documentation for the guarantees on the result.
///
/// # Panics
///
/// If `values.len()` does not match `dims`, if `spacing` is not positive and finite, or if the
/// mesh would need more than 2^31 vertices.
pub fn marching_cubes(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
) -> Mesh {
    let linear = move |a, va, b, vb| place::lerp_crossing(a, va, b, vb, iso);
    marching_cubes_with(values, dims, origin, spacing, iso, &linear)
}

/// Like [`marching_cubes`], but places each vertex with `refine(a, va, b, vb)`, where `a` and `b`
/// are the lower and upper grid nodes of a crossed edge (differing along one axis) and `va`, `vb`
/// their values, which straddle iso (one `< iso`, the other `>= iso` or NaN). This lets a caller
/// with a continuous field find the crossing by root finding.
///
/// The returned point is projected onto the edge and kept a 1e-4 fraction of the edge away from
/// both nodes (a non-finite result falls back to the midpoint); that margin is what keeps the
/// triangles non-degenerate. `refine` runs once per crossed edge, from several threads.
///
/// # Panics
///
/// As [`marching_cubes`].
pub fn marching_cubes_with(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    refine: &(dyn Fn(Vec3, f32, Vec3, f32) -> Vec3 + Sync),
) -> Mesh {
    let Some(field) = checked_samples(values, dims, origin, spacing, iso) else {
        return Mesh::default();
    };
    let crossings = all_crossings(&field, Place::Position(refine), EXTRA_FLAG);
    let parts: Vec<Part> = (0..crossings.blocks.active.len())
        .into_par_iter()
        .map(|slot| block_triangles(&field, &crossings, slot))
        .collect();
    assemble(crossings.positions, parts)
}

/// Like [`marching_cubes`], but places each vertex on the zero set of the continuous `field`
/// (whose node values `values` are) along its grid edge: the root of the cubic through the two
/// node values and the field at the edge's third points, two evaluations per vertex, exact for
/// a cubic B-spline field on its own grid. Non-finite samples fall back to regula falsi.
///
/// # Panics
///
/// As [`marching_cubes`].
pub fn marching_cubes_on_field(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    field: &dyn Field,
) -> Mesh {
    let refine = |a, va, b, vb| cubic_edge_root(field, a, va, b, vb, iso);
    marching_cubes_with(values, dims, origin, spacing, iso, &refine)
}

/// Concatenates the blocks' triangles in order, giving loop centre vertices their places after
/// the edge vertices.
fn assemble(mut positions: Vec<Vec3>, parts: Vec<Part>) -> Mesh {
    let n_triangles = parts.iter().map(|s| s.triangles.len()).sum();
    let mut triangles = Vec::with_capacity(n_triangles);
    for part in parts {
        let first = positions.len() as u32;
        assert!(
            first as usize + part.extra.len() < EXTRA_FLAG as usize,
            "too many vertices"
        );
        if part.extra.is_empty() {
            triangles.extend_from_slice(&part.triangles);
        } else {
            let resolve = |v: u32| {
                if v & EXTRA_FLAG != 0 {
                    first + (v & !EXTRA_FLAG)
                } else {
                    v
                }
            };
            triangles.extend(part.triangles.iter().map(|t| t.map(resolve)));
        }
        positions.extend_from_slice(&part.extra);
    }
    Mesh::new(positions, triangles)
}

/// Settings of [`dual_contour`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualContourOptions {
    /// Keep each vertex inside its cell (a 1e-3 fraction of the cell clear of its faces). This is
    /// what makes the geometry as safe as the topology: no two vertices coincide and no triangle
    /// is degenerate or faces the wrong way along its grid edge. Default `true`.
    pub clamp_to_cell: bool,
    /// Singular values of the tangent-plane system below this fraction of the largest are
    /// treated as zero, leaving the vertex at the crossings' mass point along those directions.
    /// Default 0.1; see `DEFAULT_SINGULAR_THRESHOLD` in the source for the measurements.
    pub singular_threshold: f32,
    /// At cells where the tangent planes meet at a feature (more than one direction passes the
    /// singular value cut), replace each crossing's plane by the tangent plane at a point this
    /// many cells further along the surface, away from the cell's mass point. Smoothed fields
    /// (a decoded B-spline) round an edge over about two cells, which tilts the normals at the
    /// crossings next to it; further away they are the faces' own. 0 keeps the crossings'
    /// planes. See `docs/algorithms.md` for the measurements behind the default.
    pub feature_offset: f32,
    /// Move the vertex of every cell without a feature onto the zero set of the field (one
    /// Newton step, kept in the cell), where marching cubes puts its vertices; the plain QEF
    /// leaves it on the least-squares plane of the crossings, which blended normals tilt.
    /// Default `true`.
    pub project_smooth: bool,
}

/// Relative singular value cut of the QEF, measured on a cube rotated 30° about x and y (side
/// 19.5 cells; mean normal deviation from the true faces) and a sphere of radius 17 cells (mean
/// vertex distance from it), with the exact field and with its cubic B-spline interpolant, as
/// the pipeline decodes it:
///
/// | threshold | 0.01 | 0.02 | 0.05 | 0.1 | 0.2 | 0.3 |
/// |---|---|---|---|---|---|---|
/// | cube, exact (°) | 0.60 | 0.60 | 0.60 | 0.60 | 0.60 | 0.60 |
/// | cube, B-spline (°) | 6.93 | 5.46 | 4.34 | 3.55 | 3.40 | 3.80 |
/// | sphere, either (cells) | 0.0110 | 0.0110 | 0.0108 | 0.0108 | 0.0108 | 0.0108 |
///
/// Exact normals do not care; the smoothed normals of a decoded field near an edge do: small
/// cuts let their spurious second and third directions pull vertices off the surface, large
/// ones drop genuine edge planes. 0.1 is within 5% of the best everywhere and keeps planes
/// meeting at smaller angles than the cube's than 0.2 would. The test
/// `default_threshold_is_near_the_best_on_cube_and_sphere` repeats the measurement.
pub const DEFAULT_SINGULAR_THRESHOLD: f32 = 0.1;

/// Default of [`DualContourOptions::feature_offset`], in cells.
pub const DEFAULT_FEATURE_OFFSET: f32 = 0.5;

impl Default for DualContourOptions {
    fn default() -> Self {
        Self {
            clamp_to_cell: true,
            singular_threshold: DEFAULT_SINGULAR_THRESHOLD,
            feature_offset: DEFAULT_FEATURE_OFFSET,
            project_smooth: true,
        }
    }
}

/// Extracts the surface `value == iso` by dual contouring: one vertex per surface component of
/// each cell, placed by the tangent planes of the continuous `field`, so sharp edges and corners
/// are reproduced rather than chamfered.
///
/// `values` are the samples of `field` at the grid nodes, laid out as for [`marching_cubes`];
/// they decide the topology (inside is `< iso`, NaN outside, ambiguous faces by the asymptotic
/// decider), and `field` only places vertices: edge crossings as in
/// [`marching_cubes_on_field`], their normals from `field.value_gradient`, and each component's
/// vertex by a truncated least-squares fit (QEF) about the crossings' mass point, refined as
/// described at [`DualContourOptions`].
///
/// Guarantees, for every input, wherever the inside region stays away from the grid border:
///
/// * **Watertight, manifold and oriented**: the mesh is the dual of the [`marching_cubes`]
///   surface (same loops, same decider), so every edge has exactly two triangles, traversed
///   once in each direction, the triangles around every vertex form one disk, and normals point
///   towards increasing values. The rare doubled dual edge (a tunnel through one face) gets a
///   midpoint vertex so this holds for the indexed triangle mesh too.
/// * **Non-degenerate** with `clamp_to_cell`: every triangle has positive area.
/// * **Deterministic**: identical output for any number of threads.
///
/// Without `clamp_to_cell` the topology is the same but vertices may leave their cells, so
/// triangles can fold over or degenerate.
///
/// # Panics
///
/// As [`marching_cubes`].
pub fn dual_contour(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    field: &dyn Field,
    options: &DualContourOptions,
) -> Mesh {
    let place = |a, va, b, vb, axis| {
        let p = cubic_edge_root(field, a, va, b, vb, iso);
        with_normal(a, b, axis, p, |p| field.value_gradient(p).1)
    };
    dual_contour_with(values, dims, origin, spacing, iso, field, options, &place)
}

/// [`dual_contour`] with the edge crossings and their normals from `place`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn dual_contour_with(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    field: &dyn Field,
    options: &DualContourOptions,
    place: &PlaceWithNormal,
) -> Mesh {
    let Some(samples) = checked_samples(values, dims, origin, spacing, iso) else {
        return Mesh::default();
    };
    let crossings = all_crossings(&samples, Place::WithNormal(place), EXTRA_FLAG);
    dual::dual_contour(&samples, &crossings, field, Placement::Planes(options))
}

/// Extracts the surface `value == iso` by surface nets: one vertex per surface component of
/// each cell, at the mean of the component's edge crossings, moved onto the zero set of `field`
/// by Newton steps along its gradient that stay inside the cell.
///
/// Inputs are as for [`dual_contour`], and so is the topology: the mesh is the dual of the
/// [`marching_cubes`] surface, with the same guarantees (watertight, manifold, oriented,
/// non-degenerate, deterministic, sparse). Crossings are the roots of the field along each edge
/// as in [`marching_cubes_on_field`]; no normals are needed, so this is cheaper than
/// [`dual_contour`] and rounds sharp features off where dual contouring keeps them.
///
/// Classic surface nets (and the `fast-surface-nets` crate) make one vertex per cell, which
/// joins two sheets passing through one cell into a vertex that is not a manifold; the tests
/// compare this function with that crate wherever every cell holds one component.
///
/// # Panics
///
/// As [`marching_cubes`].
pub fn surface_nets(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    field: &dyn Field,
) -> Mesh {
    let refine = |a, va, b, vb| cubic_edge_root(field, a, va, b, vb, iso);
    surface_nets_with(values, dims, origin, spacing, iso, field, &refine)
}

/// [`surface_nets`] with the edge crossings placed by `refine`, as in [`marching_cubes_with`].
pub(crate) fn surface_nets_with(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
    field: &dyn Field,
    refine: &(dyn Fn(Vec3, f32, Vec3, f32) -> Vec3 + Sync),
) -> Mesh {
    let Some(samples) = checked_samples(values, dims, origin, spacing, iso) else {
        return Mesh::default();
    };
    let crossings = all_crossings(&samples, Place::Position(refine), EXTRA_FLAG);
    dual::dual_contour(&samples, &crossings, field, Placement::Mean)
}

/// Checks the grid description; `None` when the grid has no cells.
fn checked_samples(
    values: &[f32],
    dims: [usize; 3],
    origin: Vec3,
    spacing: f32,
    iso: f32,
) -> Option<Samples<'_>> {
    let nodes = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    assert_eq!(
        nodes,
        Some(values.len()),
        "values do not match grid dims {dims:?}"
    );
    assert!(
        spacing.is_finite() && spacing > 0.0,
        "grid spacing must be positive, got {spacing}"
    );
    if dims.iter().any(|&d| d < 2) {
        return None;
    }
    Some(Samples {
        values,
        dims,
        origin,
        spacing,
        iso,
    })
}
