//! Contouring of sampled scalar fields into closed, manifold, consistently oriented triangle
//! meshes.
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
//! * **Deterministic**: the work runs in parallel over z slabs, but vertex and triangle order do
//!   not depend on the number of threads.
//!
//! Conventions: a node is inside when its value is `< iso` and outside otherwise (`>= iso`), so a
//! signed distance field (negative inside) gives outward-facing triangles. NaN counts as outside.
//! Where inside nodes lie on the grid border the surface is left open there; callers wanting a
//! closed mesh pad the grid with outside values.

mod crossings;
mod cube;
mod decider;
mod extract;
mod field;
mod place;
mod table;
mod triangulate;

use glam::Vec3;
use pgvol_mesh::Mesh;
use rayon::prelude::*;

use crate::crossings::{layer_crossings, Layer};
use crate::extract::{slab_triangles, Slab, Vertices, EXTRA_FLAG};
use crate::field::Field;

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
        return Mesh::default();
    }
    let field = Field {
        values,
        dims,
        origin,
        spacing,
        iso,
    };

    let layers: Vec<Layer> = (0..dims[2])
        .into_par_iter()
        .map(|z| layer_crossings(&field, z, refine))
        .collect();
    let mut base = Vec::with_capacity(layers.len());
    let mut n_vertices = 0usize;
    for layer in &layers {
        base.push(n_vertices as u32);
        n_vertices += layer.len();
    }
    assert!(n_vertices < EXTRA_FLAG as usize, "too many vertices");
    let mut positions = Vec::with_capacity(n_vertices);
    for layer in &layers {
        positions.extend_from_slice(&layer.positions);
    }

    let verts = Vertices {
        layers: &layers,
        base: &base,
        positions: &positions,
    };
    let slabs: Vec<Slab> = (0..dims[2] - 1)
        .into_par_iter()
        .map(|k| slab_triangles(&field, &verts, k))
        .collect();
    drop(layers);

    assemble(positions, slabs)
}

/// Concatenates the slabs in order, giving loop centre vertices their places after the edge
/// vertices.
fn assemble(mut positions: Vec<Vec3>, slabs: Vec<Slab>) -> Mesh {
    let n_triangles = slabs.iter().map(|s| s.triangles.len()).sum();
    let mut triangles = Vec::with_capacity(n_triangles);
    for slab in slabs {
        let first = positions.len() as u32;
        assert!(
            first as usize + slab.extra.len() < EXTRA_FLAG as usize,
            "too many vertices"
        );
        if slab.extra.is_empty() {
            triangles.extend_from_slice(&slab.triangles);
        } else {
            let resolve = |v: u32| {
                if v & EXTRA_FLAG != 0 {
                    first + (v & !EXTRA_FLAG)
                } else {
                    v
                }
            };
            triangles.extend(slab.triangles.iter().map(|t| t.map(resolve)));
        }
        positions.extend_from_slice(&slab.extra);
    }
    Mesh::new(positions, triangles)
}
