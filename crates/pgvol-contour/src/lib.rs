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
//!   [`contour_volume`] skips that read too: it evaluates the field only in the bricks of nodes
//!   the level set may cross, found from the coefficients, and keeps no array of the grid's
//!   nodes, so its time and memory follow the surface.
//!
//! Conventions: a node is inside when its value is `< iso` and outside otherwise (`>= iso`), so a
//! signed distance field (negative inside) gives outward-facing triangles. NaN counts as outside.
//! Where inside nodes lie on the grid border the surface is left open there; callers wanting a
//! closed mesh pad the grid with outside values.

#![cfg_attr(not(test), deny(clippy::print_stdout, clippy::print_stderr))]

mod blocks;
mod cell_set;
mod cells;
mod components;
mod crossings;
mod cube;
mod cubic_eval;
mod decider;
mod dual;
mod dual_methods;
mod dual_options;
mod edge_cubic;
mod extract;
mod field;
mod grids;
mod marching;
mod place;
mod project;
mod qef;
mod quads;
mod quality;
mod root;
mod runs;
mod samples;
mod sparse_sample;
mod support;
mod table;
#[cfg(test)]
mod test_volumes;
mod triangulate;
mod volume;
mod volume_root;
mod window_or;

pub use cell_set::CellSet;
pub use dual::DualMesh;
pub use dual_methods::{dual_contour, surface_nets};
pub use dual_options::{
    DualContourOptions, StoredVertices, DEFAULT_FEATURE_OFFSET, DEFAULT_SINGULAR_THRESHOLD,
    MAX_OUTSIDE_REACH,
};
pub use field::Field;
pub use grids::{resampled_grid, resampled_grid_of};
pub use marching::{marching_cubes, marching_cubes_on_field, marching_cubes_with};
pub use pgvol_core::progress::Report;
pub use quality::min_angle_histogram;
pub use runs::{contour_runs, CoefficientWindows, Occupied, RunPart, RunsError, RUN_LAYERS};
pub use volume::{
    contour_field, contour_field_hermite, contour_sampled, contour_volume, contour_volume_placing,
    dual_contour_interior, dual_vertices_interior, EdgeHermite, Method, SamplesError,
};
